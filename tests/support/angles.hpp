#pragma once
// One degree in radians, for test poses written in degrees.
namespace sflsh::testing {

inline constexpr double kDeg = 3.14159265358979323846 / 180.0;

}  // namespace sflsh::testing
