// The pieces every HTML report is built from (reconstruct, compare, demo), so that they read the
// same: headings, paragraphs, tables, images, SVG line plots and histograms, links and collapsed
// blocks, in one self-contained page (images are files beside it, linked by relative path).
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
  double stroke_width = 2;                        // pixels
};

struct PlotStyle {
  int width = 640, height = 300;  // pixels
  bool from_zero = true;          // axes start at 0 (else at the data's smallest value)
  bool equal_aspect = false;      // one unit is as long on both axes (a map, a trajectory)
};

// A line plot as inline SVG, with ticks, grid and a legend.
std::string LinePlotSvg(const std::vector<PlotSeries>& series, const std::string& x_label,
                        const std::string& y_label, const PlotStyle& style = {});

// A histogram as inline SVG: `values` counted in `bins` equal bins over [0, max_value] (larger
// values in the last bin), bar height the share of all values.
std::string HistogramSvg(const std::vector<double>& values, double max_value, int bins,
                         const std::string& x_label, const std::string& color = "#2166ac");

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);
  void Heading(const std::string& text);
  void Paragraph(const std::string& text);
  void Table(const std::vector<std::string>& header,
             const std::vector<std::vector<std::string>>& rows);
  // The same with links: hrefs[i][j] (relative to the report; empty = none) on cell rows[i][j].
  void LinkedTable(const std::vector<std::string>& header,
                   const std::vector<std::vector<std::string>>& rows,
                   const std::vector<std::vector<std::string>>& hrefs);
  // Images side by side, each with its caption (paths relative to the report).
  void Images(const std::vector<std::pair<std::string, std::string>>& images, int width = 480);
  void Figure(const std::string& svg, const std::string& caption);
  void Preformatted(const std::string& text);
  // Markup as it is (the caller's own, never text from input files).
  void RawHtml(const std::string& html);
  // A collapsed block: `summary` shown, `text` preformatted inside.
  void Details(const std::string& summary, const std::string& text);
  // A list of links (href relative to the report, text) with a description after each.
  void Links(const std::vector<std::vector<std::string>>& href_text_description);
  // The page. Once loaded, its <html> element carries data-images="L/N": L of its N images loaded
  // (what tests read back through a headless browser).
  std::string Html() const;

 private:
  std::string title_;
  std::string body_;
};

}  // namespace gf
