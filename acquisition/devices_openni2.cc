// OpenNI2 half of devices.h; compiled against OpenNI2 when GF_HAVE_OPENNI2, else a stub.
#include <stdexcept>

#include "acquisition/devices.h"

#if GF_HAVE_OPENNI2
#include <OpenNI.h>
#endif

namespace gf {

#if GF_HAVE_OPENNI2

bool OpenNI2Available() { return true; }

std::vector<std::string> ListOpenNI2Devices() {
  if (openni::OpenNI::initialize() != openni::STATUS_OK)
    throw std::runtime_error(std::string("OpenNI2 initialisation failed: ") +
                             openni::OpenNI::getExtendedError());
  openni::Array<openni::DeviceInfo> infos;
  openni::OpenNI::enumerateDevices(&infos);
  std::vector<std::string> uris;
  for (int i = 0; i < infos.getSize(); ++i) uris.emplace_back(infos[i].getUri());
  openni::OpenNI::shutdown();
  return uris;
}

#else

namespace {
[[noreturn]] void NoOpenNI2() {
  throw std::runtime_error(
      "GlassFusion was built without OpenNI2: install libopenni2-dev and rebuild with "
      "-DGF_WITH_OPENNI2=ON");
}
}  // namespace

bool OpenNI2Available() { return false; }
std::vector<std::string> ListOpenNI2Devices() { NoOpenNI2(); }

#endif

}  // namespace gf
