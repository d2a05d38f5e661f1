#pragma once
// An HDF5 identifier closed when it goes out of scope (the xdmf series' writer and reader).
#include <hdf5.h>

namespace sflsh::xdmf {

struct Handle {
  hid_t id;
  herr_t (*close)(hid_t);
  Handle(hid_t handle, herr_t (*closer)(hid_t)) : id(handle), close(closer) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id >= 0) close(id);
  }
};

}  // namespace sflsh::xdmf
