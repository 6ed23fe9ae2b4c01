// Linked into every test under ThreadSanitizer (make tsan): OpenCV's parallel loops run on the
// calling thread. Its TBB worker pool is not instrumented, so TSan cannot see TBB's own
// synchronisation and reports every parallel_for_ as a race; the threads under test are ours.
#include <opencv2/core/utility.hpp>

namespace {

struct SerialOpenCv {
  SerialOpenCv() { cv::setNumThreads(0); }
} serial_opencv;

}  // namespace
