#include "kernel/embree_device.h"

#include <cstdio>

#include "yarf/error.h"

namespace yarf {
namespace {
void ReportError(void*, RTCError code, const char* message) {
  std::fprintf(stderr, "embree error %d: %s\n", int(code), message ? message : "");
}
}  // namespace

EmbreeDevice::EmbreeDevice(const char* config) : device_(rtcNewDevice(config)) {
  if (!device_) throw Error("cannot create the Embree device");
  rtcSetDeviceErrorFunction(device_, ReportError, nullptr);
}

EmbreeDevice::~EmbreeDevice() { rtcReleaseDevice(device_); }

void EmbreeDevice::Check(const std::string& what) const {
  const RTCError code = rtcGetDeviceError(device_);
  if (code != RTC_ERROR_NONE)
    throw Error(what + ": Embree error " + std::to_string(int(code)));
}

}  // namespace yarf
