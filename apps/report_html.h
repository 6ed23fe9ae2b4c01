// The pieces every HTML report is built from (compare, demo), so that they read the same: headings,
// paragraphs, tables, images and SVG line plots, in one self-contained page (images are files
// beside it, linked by relative path).
//
// Usage:
//   gf::HtmlReport r("GlassFusion compare");
//   r.Table({"material", "with fill", "without"}, rows);
//   r.Figure(gf::LinePlotSvg({{"with fill", "#1b7837", points}}, "frame", "surfels"), "caption");
//   WriteTextFileAtomically("report.html", r.Html());
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace gf {

std::string HtmlEscape(const std::string& text);

struct PlotSeries {
  std::string name;
  std::string color;                              // CSS colour
  std::vector<std::pair<double, double>> points;  // (x, y)
};

// A line plot as inline SVG, axes from 0 to the largest value, with ticks and a legend.
std::string LinePlotSvg(const std::vector<PlotSeries>& series, const std::string& x_label,
                        const std::string& y_label, int width = 640, int height = 300);

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);
  void Heading(const std::string& text);
  void Paragraph(const std::string& text);
  void Table(const std::vector<std::string>& header,
             const std::vector<std::vector<std::string>>& rows);
  // Images side by side, each with its caption (paths relative to the report).
  void Images(const std::vector<std::pair<std::string, std::string>>& images, int width = 480);
  void Figure(const std::string& svg, const std::string& caption);
  void Preformatted(const std::string& text);
  std::string Html() const;

 private:
  std::string title_;
  std::string body_;
};

}  // namespace gf
