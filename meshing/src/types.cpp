// Names of the enums of types.hpp (stored in files and printed in messages).
#include <sflsh/meshing/types.hpp>

namespace sflsh::meshing {

const char* part_name(Part part) {
  switch (part) {
    case Part::torso:
      return "torso";
    case Part::left_upper_arm:
      return "left_upper_arm";
    case Part::right_upper_arm:
      return "right_upper_arm";
    case Part::left_thigh:
      return "left_thigh";
    case Part::right_thigh:
      return "right_thigh";
  }
  return "unknown";
}

}  // namespace sflsh::meshing
