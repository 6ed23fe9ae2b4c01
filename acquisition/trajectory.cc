#include "acquisition/trajectory.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace gf {
namespace {

bool IsBlankOrComment(const std::string& line) {
  for (char c : line) {
    if (c == '#') return true;
    if (!std::isspace(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

std::string LineError(int line_number, const std::string& what) {
  return "line " + std::to_string(line_number) + ": " + what;
}

std::string FormatDouble(double v, int precision) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", precision, v);
  return buffer;
}

}  // namespace

Trajectory ReadTumTrajectory(const std::string& path) {
  std::istringstream in(ReadTextFile(path));
  Trajectory trajectory;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (IsBlankOrComment(line)) continue;
    std::istringstream fields(line);
    StampedPose pose;
    double tx, ty, tz, qx, qy, qz, qw;
    if (!(fields >> pose.timestamp_text))
      throw InputError(path, LineError(line_number, "missing timestamp"));
    try {
      size_t used = 0;
      pose.timestamp = std::stod(pose.timestamp_text, &used);
      if (used != pose.timestamp_text.size()) throw std::invalid_argument("trailing characters");
    } catch (const std::exception&) {
      throw InputError(path,
                       LineError(line_number, "bad timestamp \"" + pose.timestamp_text + "\""));
    }
    if (!(fields >> tx >> ty >> tz >> qx >> qy >> qz >> qw))
      throw InputError(path, LineError(line_number, "expected 8 numbers: t tx ty tz qx qy qz qw"));
    const Eigen::Quaterniond q(qw, qx, qy, qz);
    if (!std::isfinite(q.norm()) || std::abs(q.norm() - 1.0) > 1e-2)
      throw InputError(path, LineError(line_number, "quaternion is not unit length"));
    pose.world_from_camera = SE3(q, Eigen::Vector3d(tx, ty, tz));
    trajectory.push_back(pose);
  }
  if (trajectory.empty()) throw InputError(path, "no poses in trajectory");
  return trajectory;
}

void WriteTumTrajectory(const std::string& path, const Trajectory& trajectory) {
  std::ostringstream out;
  out << "# timestamp tx ty tz qx qy qz qw (world_from_camera)\n";
  for (const StampedPose& p : trajectory) {
    const Eigen::Vector3d& t = p.world_from_camera.translation();
    const Eigen::Quaterniond& q = p.world_from_camera.rotation();
    out << (p.timestamp_text.empty() ? FormatDouble(p.timestamp, 6) : p.timestamp_text);
    for (double v : {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()})
      out << ' ' << FormatDouble(v, 9);
    out << '\n';
  }
  WriteTextFileAtomically(path, out.str());
}

Trajectory ReadRedwoodLog(const std::string& path) {
  std::istringstream in(ReadTextFile(path));
  Trajectory trajectory;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (IsBlankOrComment(line)) continue;
    std::istringstream header(line);
    long id0 = 0, id1 = 0, count = 0;
    if (!(header >> id0 >> id1 >> count))
      throw InputError(path, LineError(line_number, "expected a header of three integers"));
    Eigen::Matrix4d m;
    for (int row = 0; row < 4; ++row) {
      if (!std::getline(in, line))
        throw InputError(path, LineError(line_number, "truncated: matrix has fewer than 4 rows"));
      ++line_number;
      std::istringstream values(line);
      for (int col = 0; col < 4; ++col)
        if (!(values >> m(row, col)))
          throw InputError(path, LineError(line_number, "expected 4 numbers in a matrix row"));
    }
    if (!m.allFinite() || (m.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-6)
      throw InputError(path, LineError(line_number, "not a rigid 4x4 matrix"));
    const double det = m.topLeftCorner<3, 3>().determinant();
    if (std::abs(det - 1.0) > 1e-2)
      throw InputError(path, LineError(line_number, "rotation block is not a rotation"));
    StampedPose pose;
    pose.timestamp = static_cast<double>(id0);
    pose.timestamp_text = std::to_string(id0);
    pose.world_from_camera = SE3::FromMatrix(m);
    trajectory.push_back(pose);
  }
  if (trajectory.empty()) throw InputError(path, "no poses in trajectory");
  return trajectory;
}

void WriteRedwoodLog(const std::string& path, const Trajectory& trajectory) {
  std::ostringstream out;
  for (const StampedPose& p : trajectory) {
    const long i = std::lround(p.timestamp);
    out << i << ' ' << i << ' ' << i + 1 << '\n';
    const Eigen::Matrix4d m = p.world_from_camera.Matrix();
    for (int row = 0; row < 4; ++row) {
      for (int col = 0; col < 4; ++col) out << (col ? " " : "") << FormatDouble(m(row, col), 12);
      out << '\n';
    }
  }
  WriteTextFileAtomically(path, out.str());
}

Trajectory ReadTrajectory(const std::string& path) {
  const bool is_log = path.size() >= 4 && path.compare(path.size() - 4, 4, ".log") == 0;
  return is_log ? ReadRedwoodLog(path) : ReadTumTrajectory(path);
}

std::string GroundTruthBeside(const std::string& input) {
  for (const char* name : {"/groundtruth.txt", "/groundtruth.log"})
    if (IsRegularFile(input + name)) return input + name;
  return "";
}

}  // namespace gf
