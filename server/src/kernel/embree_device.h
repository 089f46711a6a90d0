// The process's Embree device, with its error callback always installed.
#pragma once

#include <embree3/rtcore.h>

#include <string>

namespace yarf {

class EmbreeDevice {
 public:
  EmbreeDevice();
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
