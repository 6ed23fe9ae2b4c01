#include "apps/report_html.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace gf {
namespace {

// A round step for about `ticks` ticks up to `range`.
double NiceStep(double range, int ticks) {
  const double raw = range / std::max(1, ticks);
  const double magnitude = std::pow(10.0, std::floor(std::log10(std::max(raw, 1e-12))));
  for (double f : {1.0, 2.0, 5.0, 10.0})
    if (f * magnitude >= raw) return f * magnitude;
  return 10 * magnitude;
}

std::string Number(double v) {
  char buffer[32];
  if (std::abs(v) >= 1e6)
    std::snprintf(buffer, sizeof(buffer), "%.1fM", v / 1e6);
  else if (std::abs(v) >= 1e4)
    std::snprintf(buffer, sizeof(buffer), "%.0fk", v / 1e3);
  else
    std::snprintf(buffer, sizeof(buffer), "%g", v);
  return buffer;
}

}  // namespace

std::string HtmlEscape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string LinePlotSvg(const std::vector<PlotSeries>& series, const std::string& x_label,
                        const std::string& y_label, int width, int height) {
  double max_x = 0, max_y = 0;
  for (const PlotSeries& s : series)
    for (const auto& [x, y] : s.points) max_x = std::max(max_x, x), max_y = std::max(max_y, y);
  if (max_x <= 0) max_x = 1;
  if (max_y <= 0) max_y = 1;
  const double sx = NiceStep(max_x, 6), sy = NiceStep(max_y, 5);
  max_x = std::ceil(max_x / sx) * sx;
  max_y = std::ceil(max_y / sy) * sy;
  const int left = 60, right = 20, top = 20, bottom = 40;
  const double w = width - left - right, h = height - top - bottom;
  auto px = [&](double x) { return left + w * x / max_x; };
  auto py = [&](double y) { return top + h * (1 - y / max_y); };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"11\">";
  svg << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << w << "\" height=\"" << h
      << "\" fill=\"none\" stroke=\"#999\"/>";
  for (double x = 0; x <= max_x + 1e-9; x += sx)
    svg << "<text x=\"" << px(x) << "\" y=\"" << top + h + 15 << "\" text-anchor=\"middle\">"
        << Number(x) << "</text>";
  for (double y = 0; y <= max_y + 1e-9; y += sy)
    svg << "<line x1=\"" << left << "\" x2=\"" << left + w << "\" y1=\"" << py(y) << "\" y2=\""
        << py(y) << "\" stroke=\"#eee\"/><text x=\"" << left - 5 << "\" y=\"" << py(y) + 4
        << "\" text-anchor=\"end\">" << Number(y) << "</text>";
  svg << "<text x=\"" << left + w / 2 << "\" y=\"" << height - 5 << "\" text-anchor=\"middle\">"
      << HtmlEscape(x_label) << "</text><text x=\"12\" y=\"" << top + h / 2
      << "\" text-anchor=\"middle\" transform=\"rotate(-90 12 " << top + h / 2 << ")\">"
      << HtmlEscape(y_label) << "</text>";
  for (size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    svg << "<polyline fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\"2\" points=\"";
    for (const auto& [x, y] : s.points) svg << px(x) << "," << py(y) << " ";
    svg << "\"/><rect x=\"" << left + 10 << "\" y=\"" << top + 8 + 16 * i
        << "\" width=\"12\" height=\"3\" fill=\"" << s.color << "\"/><text x=\"" << left + 28
        << "\" y=\"" << top + 13 + 16 * i << "\">" << HtmlEscape(s.name) << "</text>";
  }
  svg << "</svg>";
  return svg.str();
}

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

void HtmlReport::Heading(const std::string& text) {
  body_ += "<h2>" + HtmlEscape(text) + "</h2>\n";
}

void HtmlReport::Paragraph(const std::string& text) {
  body_ += "<p>" + HtmlEscape(text) + "</p>\n";
}

void HtmlReport::Table(const std::vector<std::string>& header,
                       const std::vector<std::vector<std::string>>& rows) {
  body_ += "<table><tr>";
  for (const std::string& h : header) body_ += "<th>" + HtmlEscape(h) + "</th>";
  body_ += "</tr>\n";
  for (const auto& row : rows) {
    body_ += "<tr>";
    for (const std::string& cell : row) body_ += "<td>" + HtmlEscape(cell) + "</td>";
    body_ += "</tr>\n";
  }
  body_ += "</table>\n";
}

void HtmlReport::Images(const std::vector<std::pair<std::string, std::string>>& images, int width) {
  body_ += "<div class=\"row\">";
  for (const auto& [path, caption] : images)
    body_ += "<figure><img src=\"" + HtmlEscape(path) + "\" width=\"" + std::to_string(width) +
             "\" alt=\"" + HtmlEscape(caption) + "\"><figcaption>" + HtmlEscape(caption) +
             "</figcaption></figure>";
  body_ += "</div>\n";
}

void HtmlReport::Figure(const std::string& svg, const std::string& caption) {
  body_ += "<figure>" + svg + "<figcaption>" + HtmlEscape(caption) + "</figcaption></figure>\n";
}

void HtmlReport::Preformatted(const std::string& text) {
  body_ += "<pre>" + HtmlEscape(text) + "</pre>\n";
}

std::string HtmlReport::Html() const {
  return "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + HtmlEscape(title_) +
         "</title><style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px "
         "10px;text-align:right}th{background:#f4f4f4}.row{display:flex;gap:16px;flex-wrap:wrap}"
         "figure{margin:0.5em 0}figcaption{font-size:0.9em;color:#555}pre{background:#f7f7f7;"
         "padding:8px;overflow-x:auto}</style></head><body>\n<h1>" +
         HtmlEscape(title_) + "</h1>\n" + body_ + "</body></html>\n";
}

}  // namespace gf
