#include "apps/demo.h"

#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"
#include "apps/info.h"
#include "apps/progress.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

std::string HtmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string Percent(double f) {
  std::ostringstream s;
  s.precision(1);
  s << std::fixed << 100.0 * f << "%";
  return s.str();
}

}  // namespace

void RunDemo(const std::string& out_dir, const std::string& data_dir_arg) {
  const std::string data_dir = data_dir_arg.empty() ? "../shared/datasets" : data_dir_arg;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw InputError(out_dir, "cannot create output folder: " + ec.message());

  nlohmann::ordered_json report;
  report["data"] = data_dir;
  report["inputs"] = nlohmann::json::array();
  std::vector<std::string> inputs;
  if (IsDirectory(data_dir)) {
    for (const auto& e : fs::directory_iterator(data_dir))
      if (e.is_directory() && !DetectInputKind(e.path().string()).empty())
        inputs.push_back(e.path().string());
  }
  std::sort(inputs.begin(), inputs.end());
  for (const std::string& input : inputs) {
    TerminalProgress progress("demo: " + fs::path(input).filename().string(), std::nullopt);
    report["inputs"].push_back(InputInfo(input, {}, [&](int d, int) { progress.Update(d); }));
  }

  std::ostringstream html;
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>GlassFusion demo</title>"
          "<style>body{font-family:sans-serif;margin:2em}td,th{padding:4px 10px;border-bottom:1px "
          "solid #ccc;text-align:right}td:first-child,th:first-child{text-align:left}</style>"
          "</head><body><h1>GlassFusion demo</h1>";
  html << "<p>Depth holes in the inputs found under <code>" << HtmlEscape(data_dir)
       << "</code>. These holes (no return on glass, specular and dark surfaces) are what "
          "GlassFusion's stereo fill targets. Reconstruction and stereo fill are not built yet; "
          "this report grows with the pipeline.</p>";
  if (inputs.empty()) {
    html << "<p><b>No readable dataset folders found.</b></p>";
  } else {
    html << "<table><tr><th>input</th><th>kind</th><th>frames</th><th>size</th><th>depth</th>"
            "<th>holes</th><th>no return</th><th>out of range</th></tr>";
    for (const auto& j : report["inputs"]) {
      html << "<tr><td>" << HtmlEscape(fs::path(j["input"].get<std::string>()).filename().string())
           << "</td><td>" << j["source"].get<std::string>() << "</td><td>" << j["frames"]
           << "</td><td>" << j["width"] << "x" << j["height"] << "</td><td>"
           << j["depth_convention"].get<std::string>() << "</td><td>" << Percent(j["hole_fraction"])
           << "</td><td>" << Percent(j["holes"]["no_return"]) << "</td><td>"
           << Percent(j["holes"]["out_of_range"]) << "</td></tr>";
    }
    html << "</table>";
  }
  html << "</body></html>\n";

  WriteTextFileAtomically((fs::path(out_dir) / "report.json").string(), report.dump(2) + "\n");
  WriteTextFileAtomically((fs::path(out_dir) / "report.html").string(), html.str());
  std::cout << "demo: " << inputs.size() << " inputs summarised; report in "
            << (fs::path(out_dir) / "report.html").string() << std::endl;
}

}  // namespace gf
