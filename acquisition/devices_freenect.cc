// libfreenect half of devices.h; compiled against libfreenect when GF_HAVE_FREENECT, else a stub.
#include <stdexcept>

#include "acquisition/devices.h"

#if GF_HAVE_FREENECT
#include <libfreenect.h>
#endif

namespace gf {

#if GF_HAVE_FREENECT

bool FreenectAvailable() { return true; }

int CountFreenectDevices() {
  freenect_context* context = nullptr;
  if (freenect_init(&context, nullptr) < 0 || context == nullptr)
    throw std::runtime_error("libfreenect initialisation failed (no USB access?)");
  const int count = freenect_num_devices(context);
  freenect_shutdown(context);
  if (count < 0) throw std::runtime_error("libfreenect could not enumerate devices");
  return count;
}

#else

namespace {
[[noreturn]] void NoFreenect() {
  throw std::runtime_error(
      "GlassFusion was built without libfreenect: install libfreenect-dev and rebuild with "
      "-DGF_WITH_FREENECT=ON");
}
}  // namespace

bool FreenectAvailable() { return false; }
int CountFreenectDevices() { NoFreenect(); }

#endif

}  // namespace gf
