#pragma once
// Private helpers around the HDF5 C++ API: silence HDF5's error stack printing, turn H5::Exception into
// one-line sflsh::Error messages, and read/write the attributes of a file or dataset.
#include <sflsh/validate/dyna_file.hpp>

#include <H5Cpp.h>

#include <string>

namespace sflsh::validate::detail {

/// Switches off HDF5's automatic error printing (the C stack and the C++ wrapper), so the user sees only
/// our message. Idempotent; called before every use of the library.
void quiet_hdf5();

/// "H5File::openDataSet: unable to open dataset" → a short detail for our messages.
std::string describe(const H5::Exception& e);

/// Largest number of values of one numeric attribute we read (a subject's β has 10).
inline constexpr std::size_t kMaxAttributeValues = 1000000;

/// Reads every numeric and string attribute of `object` (others are skipped); `where` ("<file>" or
/// "<file>: <dataset>") names it when an attribute is above kMaxAttributeValues.
Attributes read_attributes(const H5::H5Object& object, const std::string& where);
/// Writes `attributes` on `object` (a number vector of size 1 as a scalar, strings variable-length).
void write_attributes(H5::H5Object& object, const Attributes& attributes);

}  // namespace sflsh::validate::detail
