// The process's Embree device, with its error callback always installed.
#pragma once

#include <embree3/rtcore.h>

#include <string>

namespace yarf {

class EmbreeDevice {
 public:
  // `config`: Embree's device configuration ("isa=avx2" caps the
  // instruction set, as tests do to run the 8-wide packets anywhere).
  explicit EmbreeDevice(const char* config = nullptr);
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }
  // Throws Error with Embree's last error message, if any.
  void Check(const std::string& what) const;

 private:
  RTCDevice device_;
};

}  // namespace yarf
