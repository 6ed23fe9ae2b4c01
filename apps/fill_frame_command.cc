// `glassfusion fill-frame`: its options and help, on the CLI11 app (commands.cc registers it).
#include <iostream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "runs/fill_frame.h"

namespace gf {

void AddFillFrameCommand(CLI::App& app) {
  auto options = std::make_shared<FillFrameOptions>();
  CLI::App* cmd = app.add_subcommand(
      "fill-frame",
      "clear glass in one RGB-D frame: find it standing on its support and put its surface's "
      "depth where the sensor read nothing or read through it");
  cmd->footer(
      "DEPTH: 16-bit PNG in camera.json's depth_scale units, OpenEXR float metres, or OpenCV "
      "FileStorage (.xml/.yml/.json[.gz], node depth_image or the first) float metres.\n"
      "Example: glassfusion fill-frame --color rgb.jpg --depth depth.exr --camera camera.json "
      "--out out\n"
      "Writes: OUT/depth_filled.png (16-bit millimetres), OUT/glass_mask.png (255 = glass), "
      "OUT/glass_overlay.png (the colour: glass cyan, pixels given its depth orange), "
      "OUT/fill_frame.json (the support plane, each glass region, pixels changed).");
  cmd->add_option("--color", options->color_file, "colour image")->required();
  cmd->add_option("--depth", options->depth_file, "depth image, registered to the colour")
      ->required();
  cmd->add_option("--camera", options->camera_file, "camera.json of the colour camera")->required();
  cmd->add_option("--out", options->out_dir, "output folder (created if missing)")->required();
  cmd->add_option("--mask", options->mask_file,
                  "the glass's pixels (non-zero) when known: used instead of finding them");
  auto boxes = std::make_shared<std::vector<std::string>>();
  cmd->add_option("--box", *boxes,
                  "x,y,w,h: a box round one glass object (colour pixels; repeat for each): the "
                  "glass in it is cut out by colour (GrabCut) instead of found from the depth");
  cmd->callback([options, boxes] {
    for (const std::string& box : *boxes) options->boxes.push_back(ParseBox(box, "--box"));
    std::cout << "fill-frame: " << RunFillFrame(*options).BriefReport() << std::endl;
  });
}

}  // namespace gf
