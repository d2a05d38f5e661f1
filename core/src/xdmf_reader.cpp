// Reading back an XDMF 3 + HDF5 series of xdmf::Series (xdmf_reader.hpp).
#include "hdf5_handle.hpp"

#include <sflsh/core/error.hpp>
#include <sflsh/core/xdmf_reader.hpp>

#include <fmt/format.h>
#include <hdf5.h>
#include <vtkSmartPointer.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLUtilities.h>

#include <algorithm>
#include <sstream>

namespace sflsh::xdmf {

namespace fs = std::filesystem;

namespace {

std::string trimmed(const char* text) {
  std::string s = text == nullptr ? "" : text;
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
}

/// The nested elements of `parent` named `name`.
std::vector<vtkXMLDataElement*> children(vtkXMLDataElement* parent, const char* name) {
  std::vector<vtkXMLDataElement*> out;
  for (int i = 0; i < parent->GetNumberOfNestedElements(); ++i) {
    vtkXMLDataElement* child = parent->GetNestedElement(i);
    if (child->GetName() != nullptr && std::string(child->GetName()) == name) out.push_back(child);
  }
  return out;
}

}  // namespace

SeriesReader::SeriesReader(fs::path xmf) : xmf_(std::move(xmf)) {
  const std::string where = xmf_.string();
  require(fs::is_regular_file(xmf_), "{}: no such file, expected the .xmf of an xdmf series", where);
  vtkSmartPointer<vtkXMLDataElement> root;
  root.TakeReference(vtkXMLUtilities::ReadElementFromFile(xmf_.c_str()));
  require(root != nullptr && root->GetName() != nullptr && std::string(root->GetName()) == "Xdmf",
          "{}: not an XDMF file (expected an <Xdmf> root element)", where);
  vtkXMLDataElement* domain = root->FindNestedElementWithName("Domain");
  require(domain != nullptr, "{}: no <Domain>", where);
  vtkXMLDataElement* collection = domain->FindNestedElementWithName("Grid");
  require(collection != nullptr && trimmed(collection->GetAttribute("CollectionType")) == "Temporal",
          "{}: expected a temporal collection of grids (<Grid CollectionType=\"Temporal\">)", where);

  // "<file>.h5:/path" with its dimensions "rows [columns]".
  const auto reference = [&](vtkXMLDataElement* item, const std::string& what) {
    require(item != nullptr, "{}: {} has no <DataItem>", where, what);
    require(trimmed(item->GetAttribute("Format")) == "HDF", "{}: {}: expected Format=\"HDF\"", where, what);
    const std::string text = trimmed(item->GetCharacterData());
    const auto colon = text.find(':');
    require(colon != std::string::npos && colon > 0, "{}: {}: '{}' is not '<file>.h5:/dataset'", where, what, text);
    const fs::path h5 = xmf_.parent_path() / text.substr(0, colon);
    if (h5_.empty()) h5_ = h5;
    require(h5 == h5_, "{}: {} refers to {}, expected every dataset in {}", where, what, h5.string(), h5_.string());
    DataRef ref;
    ref.path = text.substr(colon + 1);
    std::istringstream dims(trimmed(item->GetAttribute("Dimensions")));
    require(static_cast<bool>(dims >> ref.rows) && ref.rows >= 0, "{}: {}: Dimensions is not 'rows [columns]'", where,
            what);
    if (!(dims >> ref.columns)) ref.columns = 1;
    return ref;
  };

  for (vtkXMLDataElement* grid : children(collection, "Grid")) {
    Step step;
    const std::string name = trimmed(grid->GetAttribute("Name"));
    const std::string what = fmt::format("grid '{}'", name);
    vtkXMLDataElement* time = grid->FindNestedElementWithName("Time");
    require(time != nullptr, "{}: {} has no <Time>", where, what);
    const std::string value = trimmed(time->GetAttribute("Value"));
    try {
      std::size_t used = 0;
      step.time = std::stod(value, &used);
      require(used == value.size(), "");
    } catch (const std::exception&) {
      throw_error("{}: {}: time '{}' is not a number", where, what, value);
    }
    vtkXMLDataElement* topology = grid->FindNestedElementWithName("Topology");
    require(topology != nullptr, "{}: {} has no <Topology>", where, what);
    const DataRef cells = reference(topology->FindNestedElementWithName("DataItem"), what + " topology");
    if (steps_.empty()) topology_ = cells;
    require(cells.path == topology_.path, "{}: {}: the topology changes between steps", where, what);
    vtkXMLDataElement* geometry = grid->FindNestedElementWithName("Geometry");
    require(geometry != nullptr, "{}: {} has no <Geometry>", where, what);
    step.geometry = reference(geometry->FindNestedElementWithName("DataItem"), what + " geometry");
    require(step.geometry.columns == 3, "{}: {}: geometry has {} columns, expected 3", where, what,
            step.geometry.columns);
    for (vtkXMLDataElement* attribute : children(grid, "Attribute")) {
      const std::string array = trimmed(attribute->GetAttribute("Name"));
      if (trimmed(attribute->GetAttribute("Center")) != "Node") continue;
      step.point_arrays.emplace_back(array,
                                     reference(attribute->FindNestedElementWithName("DataItem"), what + " " + array));
    }
    steps_.push_back(std::move(step));
  }
  require(!steps_.empty(), "{}: the series has no steps", where);
  require(fs::is_regular_file(h5_), "{}: its heavy data {} is missing", where, h5_.string());
}

const SeriesReader::Step& SeriesReader::step_at(std::size_t step) const {
  require(step < steps_.size(), "{}: step {} asked for, the series has {} steps", xmf_.string(), step, steps_.size());
  return steps_[step];
}

double SeriesReader::time(std::size_t step) const { return step_at(step).time; }

Eigen::MatrixXd SeriesReader::read(const DataRef& ref) const {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // failures are one sflsh error line, not HDF5's error stack
  Handle file{H5Fopen(h5_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose};
  require(file.id >= 0, "{}: cannot be opened as HDF5", h5_.string());
  Handle set{H5Dopen2(file.id, ref.path.c_str(), H5P_DEFAULT), H5Dclose};
  require(set.id >= 0, "{}: no dataset {} (named in {})", h5_.string(), ref.path, xmf_.string());
  Handle space{H5Dget_space(set.id), H5Sclose};
  hsize_t dims[2] = {0, 1};
  const int rank = H5Sget_simple_extent_ndims(space.id);
  require(rank == 1 || rank == 2, "{}: {} has {} dimensions, expected 1 or 2", h5_.string(), ref.path, rank);
  H5Sget_simple_extent_dims(space.id, dims, nullptr);
  // Bounded before allocating (a sparse chunked dataset can declare any size): 2²⁸ values, 2 GiB as doubles.
  require(dims[0] * (rank == 1 ? 1 : dims[1]) <= (hsize_t{1} << 28),
          "{}: {} has {} × {} values, above the limit of 2^28", h5_.string(), ref.path, dims[0],
          rank == 1 ? 1 : dims[1]);
  require(dims[0] == static_cast<hsize_t>(ref.rows) && (rank == 1 ? 1 : dims[1]) == static_cast<hsize_t>(ref.columns),
          "{}: {} is {} × {}, {} says {} × {}", h5_.string(), ref.path, dims[0], rank == 1 ? 1 : dims[1], xmf_.string(),
          ref.rows, ref.columns);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> values(ref.rows, ref.columns);
  require(H5Dread(set.id, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) >= 0,
          "{}: {} cannot be read as numbers", h5_.string(), ref.path);
  require(values.allFinite(), "{}: {} holds non-finite values", h5_.string(), ref.path);
  return values;
}

vtk::Cells SeriesReader::cells() const {
  const Eigen::MatrixXd values = read(topology_);
  const int nodes = steps_.front().geometry.rows;
  require(values.size() == 0 || (values.minCoeff() >= 0 && values.maxCoeff() < nodes),
          "{}: {} holds node indices outside 0 … {} (the geometry's nodes)", h5_.string(), topology_.path, nodes - 1);
  return values.cast<int>();
}

vtk::Points SeriesReader::points(std::size_t step) const {
  const Step& s = step_at(step);
  require(s.geometry.rows == steps_.front().geometry.rows, "{}: step {} has {} nodes, step 0 has {}", xmf_.string(),
          step, s.geometry.rows, steps_.front().geometry.rows);
  return read(s.geometry);
}

std::vector<std::string> SeriesReader::point_array_names(std::size_t step) const {
  std::vector<std::string> names;
  for (const auto& [name, ref] : step_at(step).point_arrays) names.push_back(name);
  return names;
}

Eigen::MatrixXd SeriesReader::point_array(std::size_t step, const std::string& name) const {
  const Step& s = step_at(step);
  const auto found = std::find_if(s.point_arrays.begin(), s.point_arrays.end(),
                                  [&](const auto& entry) { return entry.first == name; });
  if (found == s.point_arrays.end()) {
    std::string there;
    for (const auto& entry : s.point_arrays) there += (there.empty() ? "" : ", ") + entry.first;
    throw_error("{}: step {} has no node array '{}' (it has: {})", xmf_.string(), step, name,
                there.empty() ? "none" : there);
  }
  require(found->second.rows == s.geometry.rows, "{}: step {}: node array '{}' has {} rows for {} nodes", xmf_.string(),
          step, name, found->second.rows, s.geometry.rows);
  return read(found->second);
}

}  // namespace sflsh::xdmf
