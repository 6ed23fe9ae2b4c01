#include "surfels/ply.h"

#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace gf {
namespace {

struct Property {
  std::string name;
  std::string type;  // PLY type name
  size_t size = 0;
};

size_t TypeSize(const std::string& t) {
  static const std::map<std::string, size_t> sizes = {
      {"char", 1},  {"uchar", 1},   {"int8", 1},   {"uint8", 1},  {"short", 2}, {"ushort", 2},
      {"int16", 2}, {"uint16", 2},  {"int", 4},    {"uint", 4},   {"int32", 4}, {"uint32", 4},
      {"float", 4}, {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = sizes.find(t);
  return it == sizes.end() ? 0 : it->second;
}

double ReadScalar(const char* p, const std::string& t) {
  auto get = [&](auto v) {
    std::memcpy(&v, p, sizeof(v));  // little-endian hosts only (checked by the caller)
    return static_cast<double>(v);
  };
  if (t == "char" || t == "int8") return get(int8_t());
  if (t == "uchar" || t == "uint8") return get(uint8_t());
  if (t == "short" || t == "int16") return get(int16_t());
  if (t == "ushort" || t == "uint16") return get(uint16_t());
  if (t == "int" || t == "int32") return get(int32_t());
  if (t == "uint" || t == "uint32") return get(uint32_t());
  if (t == "float" || t == "float32") return get(float());
  return get(double());
}

// Sets the surfel field a PLY property names (unknown names are ignored).
void Assign(const std::string& name, double v, Surfel* s) {
  if (name == "x")
    s->position.x() = static_cast<float>(v);
  else if (name == "y")
    s->position.y() = static_cast<float>(v);
  else if (name == "z")
    s->position.z() = static_cast<float>(v);
  else if (name == "nx")
    s->normal.x() = static_cast<float>(v);
  else if (name == "ny")
    s->normal.y() = static_cast<float>(v);
  else if (name == "nz")
    s->normal.z() = static_cast<float>(v);
  else if (name == "red")
    s->red = static_cast<uint8_t>(v);
  else if (name == "green")
    s->green = static_cast<uint8_t>(v);
  else if (name == "blue")
    s->blue = static_cast<uint8_t>(v);
  else if (name == "radius")
    s->radius = static_cast<float>(v);
  else if (name == "confidence")
    s->confidence = static_cast<float>(v);
  else if (name == "source")
    s->source = static_cast<uint8_t>(v);
}

}  // namespace

std::string SurfelPlyBytes(const std::vector<Surfel>& surfels, bool normals) {
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment GlassFusion surfel map (world frame, "
            "metres)\nelement vertex "
         << surfels.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
         << (normals ? "property float nx\nproperty float ny\nproperty float nz\n" : "")
         << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
            "property float radius\nproperty float confidence\nproperty uchar source\n"
            "end_header\n";
  const size_t kRecord = (normals ? 6 : 3) * 4 + 3 + 4 + 4 + 1;
  std::string body = header.str();
  const size_t start = body.size();
  body.resize(start + surfels.size() * kRecord);
  char* p = body.data() + start;
  auto put = [&](const void* v, size_t n) {
    std::memcpy(p, v, n);
    p += n;
  };
  for (const Surfel& s : surfels) {
    put(s.position.data(), 12);
    if (normals) put(s.normal.data(), 12);
    put(&s.red, 1);
    put(&s.green, 1);
    put(&s.blue, 1);
    put(&s.radius, 4);
    put(&s.confidence, 4);
    put(&s.source, 1);
  }
  return body;
}

void WriteSurfelPly(const std::string& path, const std::vector<Surfel>& surfels) {
  const std::string bytes = SurfelPlyBytes(surfels);
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw InputError(path, "cannot open for writing");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw InputError(path, "write error (disk full?)");
  });
}

std::vector<Surfel> ReadSurfelPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, IsRegularFile(path) ? "cannot open for reading" : "file not found");
  std::string line, format;
  std::vector<Property> vertex;
  long count = -1;
  bool in_vertex = false, first_element = true;
  std::getline(in, line);
  if (line != "ply") throw InputError(path, "not a PLY file");
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (key == "format") {
      words >> format;
    } else if (key == "element") {
      std::string name;
      words >> name;
      in_vertex = first_element && name == "vertex";
      if (in_vertex) words >> count;
      if (first_element && !in_vertex) throw InputError(path, "the first element is not vertex");
      first_element = false;
    } else if (key == "property" && in_vertex) {
      Property prop;
      words >> prop.type >> prop.name;
      prop.size = TypeSize(prop.type);
      if (prop.size == 0) throw InputError(path, "unsupported vertex property type " + prop.type);
      vertex.push_back(prop);
    } else if (key == "end_header") {
      break;
    }
  }
  if (count < 0 || vertex.empty()) throw InputError(path, "no vertex element");
  std::vector<Surfel> out(static_cast<size_t>(count));
  if (format == "ascii") {
    for (Surfel& s : out)
      for (const Property& prop : vertex) {
        double v;
        if (!(in >> v)) throw InputError(path, "truncated vertex data");
        Assign(prop.name, v, &s);
      }
    return out;
  }
  if (format != "binary_little_endian") throw InputError(path, "unsupported PLY format " + format);
  size_t record = 0;
  for (const Property& prop : vertex) record += prop.size;
  std::string data(record * out.size(), '\0');
  if (!in.read(data.data(), static_cast<std::streamsize>(data.size())))
    throw InputError(path, "truncated vertex data");
  const char* p = data.data();
  for (Surfel& s : out)
    for (const Property& prop : vertex) {
      Assign(prop.name, ReadScalar(p, prop.type), &s);
      p += prop.size;
    }
  return out;
}

}  // namespace gf
