#include "hdf5_util.hpp"

#include <sflsh/core/error.hpp>

#include <vector>

namespace sflsh::validate::detail {

void quiet_hdf5() {
  H5::Exception::dontPrint();                   // the C++ wrapper's printing
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // and the C library's
}

std::string describe(const H5::Exception& e) {
  std::string what = e.getDetailMsg();
  return what.empty() ? e.getFuncName() : what;
}

Attributes read_attributes(const H5::H5Object& object, const std::string& where) {
  Attributes out;
  const int count = object.getNumAttrs();
  for (int a = 0; a < count; ++a) {
    const H5::Attribute attribute = object.openAttribute(static_cast<unsigned>(a));
    const std::string name = attribute.getName();
    const H5T_class_t type_class = attribute.getTypeClass();
    const H5::DataSpace space = attribute.getSpace();
    const auto n = static_cast<std::size_t>(space.getSimpleExtentNpoints());
    if (type_class == H5T_FLOAT || type_class == H5T_INTEGER) {
      require(n <= kMaxAttributeValues, "{}: attribute '{}': {} values, above the limit of {}", where, name, n,
              kMaxAttributeValues);
      std::vector<double> values(n);
      if (n > 0) attribute.read(H5::PredType::NATIVE_DOUBLE, values.data());
      out.numbers[name] = std::move(values);
    } else if (type_class == H5T_STRING && n == 1) {
      std::string value;
      attribute.read(attribute.getStrType(), value);
      while (!value.empty() && value.back() == '\0') value.pop_back();  // fixed-length padding
      out.strings[name] = value;
    }
  }
  return out;
}

void write_attributes(H5::H5Object& object, const Attributes& attributes) {
  for (const auto& [name, values] : attributes.numbers) {
    require(!values.empty(), "attribute '{}' has no value", name);
    const hsize_t n = values.size();
    const H5::DataSpace space = n == 1 ? H5::DataSpace(H5S_SCALAR) : H5::DataSpace(1, &n);
    H5::Attribute attribute = object.createAttribute(name, H5::PredType::IEEE_F64LE, space);
    attribute.write(H5::PredType::NATIVE_DOUBLE, values.data());
  }
  const H5::StrType string_type(H5::PredType::C_S1, H5T_VARIABLE);
  for (const auto& [name, value] : attributes.strings) {
    H5::Attribute attribute = object.createAttribute(name, string_type, H5::DataSpace(H5S_SCALAR));
    attribute.write(string_type, value);
  }
}

}  // namespace sflsh::validate::detail
