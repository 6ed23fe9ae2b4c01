// RealSense recordings: a `.bag` file as the RealSense Viewer, `rs-record` or librealsense's
// recorder writes it (a ROS 1 bag, format 2.0, chunks uncompressed, LZ4 or BZ2), read with
// Debian's librosbag_storage (no ROS installation needed).
//
// What is read, in librealsense's layout (src/media/ros/ros_file_format.h):
//  - the depth and colour image streams, `/device_D/sensor_S/<Depth|Color>_I/image/data`
//    (sensor_msgs/Image: depth `mono16` or `16UC1`; colour rgb8, bgr8, rgba8, bgra8, yuyv, uyvy
//    or mono8), paired one to one by their header stamps (the device's clock, seconds) within
//    FrameSourceOptions::max_association_dt_s; a frame's timestamp is its depth header stamp;
//  - each stream's intrinsics, `.../info/camera_info` (sensor_msgs/CameraInfo: K, and D in the
//    "Brown Conrady" model, which is OpenCV's; another model with non-zero coefficients is
//    refused: pass --camera);
//  - the depth units, `/device_D/sensor_S/option/Depth_Units/value` (or `Depth Units`, older
//    files; std_msgs/Float32, metres per unit), else the float that librealsense 2.49 and later
//    append to each depth image message;
//  - the extrinsics, `.../tf/0` (geometry_msgs/Transform from the stream group's first stream,
//    depth on a D400, to this one), giving color_from_depth; depth is then registered to colour
//    by ProcessRawDepth, as for any input whose depth is not registered.
// Where a bag holds several depth or colour streams, FrameSourceOptions::bag_depth_topic and
// bag_color_topic name the ones to read.
//
// Errors: a missing, truncated, unindexed or corrupt file, a missing stream, intrinsics or
// extrinsic, or an unsupported encoding is an InputError naming the file and what is wrong, at
// open or at the frame where it is met.
#pragma once

#include <memory>
#include <string>

#include "acquisition/frame_source.h"

namespace gf {

// Whether this build reads bags (librosbag_storage was found).
bool RealSenseBagSupported();

// Opens a RealSense .bag as a FrameSource of kind "realsense_bag".
std::unique_ptr<FrameSource> OpenRealSenseBag(const std::string& path,
                                              const FrameSourceOptions& options);

}  // namespace gf
