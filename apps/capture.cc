#include "apps/capture.h"

#include <iostream>

#include "acquisition/bounds.h"
#include "acquisition/errors.h"
#include "acquisition/frame_sink.h"
#include "acquisition/frame_source.h"
#include "apps/interrupt.h"
#include "apps/progress.h"

namespace gf {

bool CaptureOptions::Check(std::string* message) const {
  FieldCheck c(message);
  c.Require(!device.empty(), "--device: which device or recording to read")
      .Require(!out_dir.empty(), "--out: the folder to write")
      .In("--frames", frames, 0, kMaxCaptureFrames, kMoreFramesThanACapture);
  return c.ok();
}

int RunCapture(const CaptureOptions& options) {
  std::string problem;
  if (!options.Check(&problem)) throw InputError("capture", problem);
  FrameSourceOptions source_options;
  source_options.camera_file = options.camera_file;
  std::unique_ptr<FrameSource> source = OpenFrameSource(options.device, source_options);
  TumFolderSink sink(options.out_dir, source->camera_file());
  std::optional<int> total =
      options.frames > 0 ? std::optional<int>(options.frames) : source->FrameCount();
  const InterruptHandler interrupt;  // Ctrl-C ends a live capture cleanly
  TerminalProgress progress("capture", total);
  RgbdFrame frame;
  while (!*interrupt.signal() && (options.frames == 0 || sink.frames_written() < options.frames) &&
         source->Next(&frame)) {
    sink.Write(frame);
    progress.Update(sink.frames_written());
  }
  progress.Finish();
  if (sink.frames_written() == 0) throw InputError(options.device, "delivered no frames");
  sink.Close();
  std::cout << "capture: " << sink.frames_written() << " frames written to " << options.out_dir
            << std::endl;
  return sink.frames_written();
}

}  // namespace gf
