#pragma once
// An HDF5 identifier closed by the function of its kind, and the library kept from printing its
// error stack (ctk reports errors itself, naming file and dataset).
#include <hdf5.h>

namespace ctk::hdf5 {

class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  Handle(Handle&& other) noexcept : id_(other.id_), close_(other.close_) { other.id_ = -1; }
  Handle& operator=(Handle&&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

inline void quiet_library() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

}  // namespace ctk::hdf5
