#include "acquisition/devices.h"

#include <gtest/gtest.h>

namespace gf {
namespace {

// Built with OpenNI2, enumeration works without hardware and lists no device on a machine with
// none attached; built without it, the call fails with a message naming the missing library.
TEST(Devices, OpenNI2EnumeratesOrExplainsWhyNot) {
  if (OpenNI2Available()) {
    EXPECT_NO_THROW({
      const auto uris = ListOpenNI2Devices();
      for (const auto& uri : uris) EXPECT_FALSE(uri.empty());
    });
  } else {
    try {
      ListOpenNI2Devices();
      ADD_FAILURE() << "stub did not throw";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("without OpenNI2"), std::string::npos);
    }
  }
}

// Built with libfreenect, counting needs USB access: it returns a count, or (in a sandbox without
// USB) fails naming libfreenect. Built without it, the stub names the missing library.
TEST(Devices, FreenectCountsOrExplainsWhyNot) {
  try {
    const int count = CountFreenectDevices();
    EXPECT_TRUE(FreenectAvailable()) << "the stub returned a count";
    EXPECT_GE(count, 0);
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    if (FreenectAvailable()) {
      EXPECT_EQ(what.rfind("libfreenect ", 0), 0u) << what;
    } else {
      EXPECT_NE(what.find("built without libfreenect"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace gf
