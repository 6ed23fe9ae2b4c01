#include "report/report_html.h"

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
                        const std::string& y_label, const PlotStyle& style) {
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  bool first = true;
  for (const PlotSeries& s : series)
    for (const auto& [x, y] : s.points) {
      if (first && !style.from_zero) min_x = max_x = x, min_y = max_y = y;
      first = false;
      min_x = std::min(min_x, x), max_x = std::max(max_x, x);
      min_y = std::min(min_y, y), max_y = std::max(max_y, y);
    }
  const int left = 60, right = 20, top = 20, bottom = 40;
  const double w = style.width - left - right, h = style.height - top - bottom;
  if (max_x <= min_x) max_x = min_x + 1;
  if (max_y <= min_y) max_y = min_y + 1;
  if (style.equal_aspect) {  // widen the narrower range about its centre
    const double scale = std::max((max_x - min_x) / w, (max_y - min_y) / h);
    const double cx = (min_x + max_x) / 2, cy = (min_y + max_y) / 2;
    min_x = cx - scale * w / 2, max_x = cx + scale * w / 2;
    min_y = cy - scale * h / 2, max_y = cy + scale * h / 2;
  }
  const double sx = NiceStep(max_x - min_x, 6), sy = NiceStep(max_y - min_y, 5);
  if (!style.equal_aspect) {
    min_x = std::floor(min_x / sx) * sx, max_x = std::ceil(max_x / sx) * sx;
    min_y = std::floor(min_y / sy) * sy, max_y = std::ceil(max_y / sy) * sy;
  }
  auto px = [&](double x) { return left + w * (x - min_x) / (max_x - min_x); };
  auto py = [&](double y) { return top + h * (1 - (y - min_y) / (max_y - min_y)); };
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << style.width << "\" height=\""
      << style.height << "\" font-family=\"sans-serif\" font-size=\"11\">";
  svg << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << w << "\" height=\"" << h
      << "\" fill=\"none\" stroke=\"#999\"/>";
  for (double x = std::ceil(min_x / sx) * sx; x <= max_x + 1e-9 * sx; x += sx)
    svg << "<text x=\"" << px(x) << "\" y=\"" << top + h + 15 << "\" text-anchor=\"middle\">"
        << Number(std::abs(x) < 1e-9 * sx ? 0 : x) << "</text>";
  for (double y = std::ceil(min_y / sy) * sy; y <= max_y + 1e-9 * sy; y += sy)
    svg << "<line x1=\"" << left << "\" x2=\"" << left + w << "\" y1=\"" << py(y) << "\" y2=\""
        << py(y) << "\" stroke=\"#eee\"/><text x=\"" << left - 5 << "\" y=\"" << py(y) + 4
        << "\" text-anchor=\"end\">" << Number(std::abs(y) < 1e-9 * sy ? 0 : y) << "</text>";
  svg << "<text x=\"" << left + w / 2 << "\" y=\"" << style.height - 5
      << "\" text-anchor=\"middle\">" << HtmlEscape(x_label) << "</text><text x=\"12\" y=\""
      << top + h / 2 << "\" text-anchor=\"middle\" transform=\"rotate(-90 12 " << top + h / 2
      << ")\">" << HtmlEscape(y_label) << "</text>";
  for (size_t i = 0; i < series.size(); ++i) {
    const PlotSeries& s = series[i];
    svg << "<polyline fill=\"none\" stroke=\"" << s.color << "\" stroke-width=\"" << s.stroke_width
        << "\" stroke-linejoin=\"round\" points=\"";
    for (const auto& [x, y] : s.points) svg << px(x) << "," << py(y) << " ";
    svg << "\"/><rect x=\"" << left + 10 << "\" y=\"" << top + 8 + 16 * i
        << "\" width=\"12\" height=\"3\" fill=\"" << s.color << "\"/><text x=\"" << left + 28
        << "\" y=\"" << top + 13 + 16 * i << "\">" << HtmlEscape(s.name) << "</text>";
  }
  svg << "</svg>";
  return svg.str();
}

std::string HistogramSvg(const std::vector<double>& values, double max_value, int bins,
                         const std::string& x_label, const std::string& color) {
  bins = std::max(1, bins);
  std::vector<double> share(bins, 0.0);
  for (double v : values)
    share[std::clamp(static_cast<int>(v / max_value * bins), 0, bins - 1)] += 1.0 / values.size();
  const int width = 640, height = 260, left = 60, right = 20, top = 20, bottom = 40;
  const double w = width - left - right, h = height - top - bottom;
  double top_share = 0;
  for (double s : share) top_share = std::max(top_share, s);
  const double sy = NiceStep(std::max(top_share, 1e-3), 4);
  const double max_y = std::ceil(std::max(top_share, 1e-3) / sy) * sy;
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height
      << "\" font-family=\"sans-serif\" font-size=\"11\">";
  for (double y = 0; y <= max_y + 1e-9; y += sy)
    svg << "<line x1=\"" << left << "\" x2=\"" << left + w << "\" y1=\""
        << top + h * (1 - y / max_y) << "\" y2=\"" << top + h * (1 - y / max_y)
        << "\" stroke=\"#eee\"/><text x=\"" << left - 5 << "\" y=\""
        << top + h * (1 - y / max_y) + 4 << "\" text-anchor=\"end\">"
        << Number(std::round(100 * y * 10) / 10) << "%</text>";
  for (int b = 0; b < bins; ++b)
    svg << "<rect x=\"" << left + w * b / bins + 1 << "\" y=\"" << top + h * (1 - share[b] / max_y)
        << "\" width=\"" << std::max(1.0, w / bins - 2) << "\" height=\"" << h * share[b] / max_y
        << "\" fill=\"" << color << "\"/>";
  const double sx = NiceStep(max_value, 6);
  for (double x = 0; x <= max_value + 1e-9 * sx; x += sx)
    svg << "<text x=\"" << left + w * x / max_value << "\" y=\"" << top + h + 15
        << "\" text-anchor=\"middle\">" << Number(x) << (x + sx > max_value + 1e-9 * sx ? "+" : "")
        << "</text>";
  svg << "<rect x=\"" << left << "\" y=\"" << top << "\" width=\"" << w << "\" height=\"" << h
      << "\" fill=\"none\" stroke=\"#999\"/><text x=\"" << left + w / 2 << "\" y=\"" << height - 5
      << "\" text-anchor=\"middle\">" << HtmlEscape(x_label) << "</text></svg>";
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
  LinkedTable(header, rows, {});
}

void HtmlReport::LinkedTable(const std::vector<std::string>& header,
                             const std::vector<std::vector<std::string>>& rows,
                             const std::vector<std::vector<std::string>>& hrefs) {
  body_ += "<table><tr>";
  for (const std::string& h : header) body_ += "<th>" + HtmlEscape(h) + "</th>";
  body_ += "</tr>\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    body_ += "<tr>";
    for (size_t j = 0; j < rows[i].size(); ++j) {
      const std::string href = i < hrefs.size() && j < hrefs[i].size() ? hrefs[i][j] : "";
      body_ += "<td>" +
               (href.empty()
                    ? HtmlEscape(rows[i][j])
                    : "<a href=\"" + HtmlEscape(href) + "\">" + HtmlEscape(rows[i][j]) + "</a>") +
               "</td>";
    }
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

void HtmlReport::RawHtml(const std::string& html) { body_ += html; }

void HtmlReport::Preformatted(const std::string& text) {
  body_ += "<pre>" + HtmlEscape(text) + "</pre>\n";
}

void HtmlReport::Details(const std::string& summary, const std::string& text) {
  body_ += "<details><summary>" + HtmlEscape(summary) + "</summary><pre>" + HtmlEscape(text) +
           "</pre></details>\n";
}

void HtmlReport::Links(const std::vector<std::vector<std::string>>& links) {
  body_ += "<ul>";
  for (const auto& link : links)
    if (link.size() >= 2)
      body_ += "<li><a href=\"" + HtmlEscape(link[0]) + "\">" + HtmlEscape(link[1]) + "</a>" +
               (link.size() > 2 ? " &mdash; " + HtmlEscape(link[2]) : "") + "</li>";
  body_ += "</ul>\n";
}

std::string HtmlReport::Html() const {
  return "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>" + HtmlEscape(title_) +
         "</title><style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:4px "
         "10px;text-align:right}td:first-child,th:first-child{text-align:left}th{background:#"
         "f4f4f4}.row{display:flex;gap:16px;flex-wrap:wrap}"
         "figure{margin:0.5em 0}figcaption{font-size:0.9em;color:#555}pre{background:#f7f7f7;"
         "padding:8px;overflow-x:auto}</style></head><body>\n<h1>" +
         HtmlEscape(title_) + "</h1>\n" + body_ +
         "<script>addEventListener('load',()=>{const i=[...document.images];"
         "document.documentElement.dataset.images=i.filter(x=>x.complete&&x.naturalWidth>0)"
         ".length+'/'+i.length;});</script>\n</body></html>\n";
}

}  // namespace gf
