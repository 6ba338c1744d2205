#include "core/html_report.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/html_scene3d.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::report {
namespace {

constexpr double kWidth = 640.0;  // SVG plot size, CSS px
constexpr double kHeight = 400.0;
constexpr double kLeft = 70.0;  // margins for tick labels
constexpr double kRight = 20.0;
constexpr double kTop = 30.0;
constexpr double kBottom = 50.0;
const char* const kPalette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                "#9467bd", "#8c564b", "#e377c2", "#17becf"};

}  // namespace

std::string EscapeHtml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
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
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

namespace {

// Short numbers for coordinates and tick labels (no locale).
std::string Num(double v, int precision = 4) {
  if (!std::isfinite(v)) return "0";
  char buffer[64];
  const auto r =
      std::to_chars(buffer, buffer + sizeof(buffer), v, std::chars_format::general, precision);
  return std::string(buffer, r.ptr);
}

// "Nice" tick positions over [lo, hi] (Heckbert's labelling).
std::vector<double> Ticks(double lo, double hi, int target = 6) {
  std::vector<double> ticks;
  if (!(hi > lo)) return {lo};
  const double raw = (hi - lo) / target;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double residual = raw / magnitude;
  const double step = magnitude * (residual < 1.5 ? 1 : residual < 3 ? 2 : residual < 7 ? 5 : 10);
  for (double t = std::ceil(lo / step) * step; t <= hi + 1e-9 * step; t += step) {
    ticks.push_back(std::abs(t) < 1e-12 * step ? 0.0 : t);
  }
  return ticks;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void Finish() {
    if (!std::isfinite(lo)) lo = 0, hi = 1;
    if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) {
      const double pad = std::max(1e-9, 0.05 * std::abs(hi));
      lo -= pad;
      hi += pad;
    }
  }
};

// Maps data coordinates into the plot rectangle and draws axes, ticks and labels.
class Frame {
 public:
  Frame(Range x, Range y, bool y_down, bool equal_aspect) : x_(x), y_(y), y_down_(y_down) {
    x_.Finish();
    y_.Finish();
    w_ = kWidth - kLeft - kRight;
    h_ = kHeight - kTop - kBottom;
    if (equal_aspect) {
      const double sx = w_ / (x_.hi - x_.lo), sy = h_ / (y_.hi - y_.lo);
      const double s = std::min(sx, sy);
      w_ = s * (x_.hi - x_.lo);
      h_ = s * (y_.hi - y_.lo);
    }
  }
  double X(double x) const { return kLeft + (x - x_.lo) / (x_.hi - x_.lo) * w_; }
  double Y(double y) const {
    const double f = (y - y_.lo) / (y_.hi - y_.lo);
    return kTop + (y_down_ ? f : 1.0 - f) * h_;
  }
  double plot_width() const { return w_; }
  double plot_height() const { return h_; }

  std::string Axes(const std::string& x_label, const std::string& y_label,
                   bool x_ticks = true) const {
    std::string s;
    s += "<rect x='" + Num(kLeft) + "' y='" + Num(kTop) + "' width='" + Num(w_) + "' height='" +
         Num(h_) + "' fill='none' stroke='#444'/>";
    for (double t : x_ticks ? Ticks(x_.lo, x_.hi) : std::vector<double>{}) {
      const double px = X(t);
      s += "<line x1='" + Num(px) + "' y1='" + Num(kTop + h_) + "' x2='" + Num(px) + "' y2='" +
           Num(kTop + h_ + 5) + "' stroke='#444'/>";
      s += "<text x='" + Num(px) + "' y='" + Num(kTop + h_ + 18) +
           "' text-anchor='middle' class='tick'>" + Num(t) + "</text>";
    }
    for (double t : Ticks(y_.lo, y_.hi)) {
      const double py = Y(t);
      s += "<line x1='" + Num(kLeft - 5) + "' y1='" + Num(py) + "' x2='" + Num(kLeft) + "' y2='" +
           Num(py) + "' stroke='#444'/>";
      s += "<text x='" + Num(kLeft - 8) + "' y='" + Num(py + 4) +
           "' text-anchor='end' class='tick'>" + Num(t) + "</text>";
    }
    s += "<text x='" + Num(kLeft + w_ / 2) + "' y='" + Num(kTop + h_ + 40) +
         "' text-anchor='middle' class='label'>" + EscapeHtml(x_label) + "</text>";
    s += "<text transform='translate(16," + Num(kTop + h_ / 2) +
         ") rotate(-90)' text-anchor='middle' class='label'>" + EscapeHtml(y_label) + "</text>";
    return s;
  }

 private:
  Range x_, y_;
  bool y_down_;
  double w_ = 0, h_ = 0;
};

std::string OpenSvg(const std::string& title, double height = kHeight) {
  return "<figure><svg class='lc-plot' data-plot='" + EscapeHtml(title) +
         "' xmlns='http://www.w3.org/2000/svg' width='" + Num(kWidth + 90) + "' height='" +
         Num(height) + "' viewBox='0 0 " + Num(kWidth + 90) + " " + Num(height) + "'>" +
         "<text x='" + Num(kLeft) + "' y='18' class='title'>" + EscapeHtml(title) + "</text>";
}

std::string CloseSvg(const std::string& caption = "") {
  std::string s = "</svg>";
  if (!caption.empty()) s += "<figcaption>" + EscapeHtml(caption) + "</figcaption>";
  return s + "</figure>\n";
}

// Viridis-like colour ramp, t in [0, 1].
std::string Colour(double t) {
  static const double stops[5][3] = {
      {68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(t));
  const double f = t - i;
  char buffer[16];
  const auto c = [&](int k) {
    return static_cast<int>(std::lround(stops[i][k] + f * (stops[i + 1][k] - stops[i][k])));
  };
  std::snprintf(buffer, sizeof(buffer), "#%02x%02x%02x", c(0), c(1), c(2));
  return buffer;
}

}  // namespace

HtmlReport::HtmlReport(std::string title) : title_(std::move(title)) {}

void HtmlReport::AddHeading(const std::string& text) {
  body_ += "<h2>" + EscapeHtml(text) + "</h2>\n";
}

void HtmlReport::AddParagraph(const std::string& text) {
  body_ += "<p>" + EscapeHtml(text) + "</p>\n";
}

void HtmlReport::AddWarning(const std::string& text) {
  body_ += "<p class='warning'>&#9888; " + EscapeHtml(text) + "</p>\n";
}

void HtmlReport::AddKeyValues(const std::vector<std::pair<std::string, std::string>>& rows) {
  body_ += "<table class='kv'>";
  for (const auto& [key, value] : rows) {
    body_ += "<tr><th>" + EscapeHtml(key) + "</th><td>" + EscapeHtml(value) + "</td></tr>";
  }
  body_ += "</table>\n";
}

void HtmlReport::AddTable(const std::vector<std::string>& header,
                          const std::vector<std::vector<std::string>>& rows) {
  body_ += "<table><tr>";
  for (const auto& h : header) body_ += "<th>" + EscapeHtml(h) + "</th>";
  body_ += "</tr>";
  for (std::size_t r = 0; r < rows.size(); ++r) {
    LASERCELL_CHECK(rows[r].size() == header.size(), "report table row has the wrong cell count");
    body_ += "<tr>";
    for (const auto& cell : rows[r]) body_ += "<td>" + EscapeHtml(cell) + "</td>";
    body_ += "</tr>";
  }
  body_ += "</table>\n";
}

void HtmlReport::AddHistogram(const std::string& title, const std::vector<double>& values,
                              const std::string& x_label, int bins) {
  LASERCELL_CHECK(bins > 0, "histogram needs at least one bin");
  Range xr;
  for (double v : values) xr.Add(v);
  xr.Finish();
  std::vector<int> counts(static_cast<std::size_t>(bins), 0);
  const double width = (xr.hi - xr.lo) / bins;
  int finite = 0;
  for (double v : values) {
    if (!std::isfinite(v)) continue;
    ++finite;
    const int b = std::clamp(static_cast<int>((v - xr.lo) / width), 0, bins - 1);
    ++counts[static_cast<std::size_t>(b)];
  }
  Range yr;
  yr.Add(0);
  yr.Add(std::max(1, *std::max_element(counts.begin(), counts.end())));
  const Frame frame(xr, yr, false, false);
  std::string s = OpenSvg(title);
  for (int b = 0; b < bins; ++b) {
    const double x0 = frame.X(xr.lo + b * width), x1 = frame.X(xr.lo + (b + 1) * width);
    const double y0 = frame.Y(0), y1 = frame.Y(counts[static_cast<std::size_t>(b)]);
    s += "<rect x='" + Num(x0) + "' y='" + Num(y1) + "' width='" + Num(std::max(0.5, x1 - x0 - 1)) +
         "' height='" + Num(y0 - y1) + "' fill='#1f77b4'><title>" +
         Num(counts[static_cast<std::size_t>(b)]) + "</title></rect>";
  }
  s += frame.Axes(x_label, "count");
  body_ += s + CloseSvg(std::to_string(finite) + " values");
  ++num_plots_;
}

void HtmlReport::AddBars(const std::string& title, const std::vector<std::string>& labels,
                         const std::vector<double>& values, const std::string& y_label) {
  LASERCELL_CHECK(labels.size() == values.size(), "bar chart needs one label per value");
  Range xr;
  xr.Add(0);
  xr.Add(static_cast<double>(std::max<std::size_t>(1, values.size())));
  Range yr;
  yr.Add(0);
  for (double v : values) yr.Add(v);
  const Frame frame(xr, yr, false, false);
  std::string s = OpenSvg(title, kHeight + 40);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double x0 = frame.X(static_cast<double>(i) + 0.1);
    const double x1 = frame.X(static_cast<double>(i) + 0.9);
    const double v = std::isfinite(values[i]) ? values[i] : 0.0;
    const double y0 = frame.Y(std::min(0.0, v)), y1 = frame.Y(std::max(0.0, v));
    s += "<rect x='" + Num(x0) + "' y='" + Num(y1) + "' width='" + Num(x1 - x0) + "' height='" +
         Num(y0 - y1) + "' fill='#1f77b4'><title>" + EscapeHtml(labels[i]) + ": " + Num(values[i]) +
         "</title></rect>";
    if (values.size() <= 60) {
      s += "<text transform='translate(" + Num((x0 + x1) / 2) + "," + Num(kHeight - kBottom + 12) +
           ") rotate(60)' class='tick'>" + EscapeHtml(labels[i]) + "</text>";
    }
  }
  s += frame.Axes("", y_label, /*x_ticks=*/false);
  body_ += s + CloseSvg();
  ++num_plots_;
}

void HtmlReport::AddScatter(const std::string& title, const std::vector<Series>& series,
                            const PlotOptions& options) {
  Range xr, yr;
  if (options.range[1] > options.range[0] && options.range[3] > options.range[2]) {
    xr.Add(options.range[0]);
    xr.Add(options.range[1]);
    yr.Add(options.range[2]);
    yr.Add(options.range[3]);
  } else {
    for (const Series& ser : series) {
      LASERCELL_CHECK(ser.x.size() == ser.y.size(), "scatter series needs as many x as y");
      for (double v : ser.x) xr.Add(v);
      for (double v : ser.y) yr.Add(v);
    }
  }
  const Frame frame(xr, yr, options.y_down, options.equal_aspect);
  std::string s = OpenSvg(title);
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Series& ser = series[k];
    const std::string colour = kPalette[k % 8];
    if (ser.lines) {
      std::string points;
      for (std::size_t i = 0; i < ser.x.size(); ++i) {
        if (!std::isfinite(ser.x[i]) || !std::isfinite(ser.y[i])) continue;
        points += Num(frame.X(ser.x[i])) + "," + Num(frame.Y(ser.y[i])) + " ";
      }
      s += "<polyline fill='none' stroke='" + colour + "' stroke-width='1.5' points='" + points +
           "'/>";
    } else {
      // Cap the marker count so reports of large data sets stay light.
      const std::size_t stride = std::max<std::size_t>(1, ser.x.size() / 20000);
      for (std::size_t i = 0; i < ser.x.size(); i += stride) {
        if (!std::isfinite(ser.x[i]) || !std::isfinite(ser.y[i])) continue;
        s += "<circle cx='" + Num(frame.X(ser.x[i])) + "' cy='" + Num(frame.Y(ser.y[i])) +
             "' r='2' fill='" + colour + "' fill-opacity='0.7'/>";
      }
    }
    s += "<rect x='" + Num(kWidth - kRight + 5) + "' y='" + Num(kTop + 16.0 * k) +
         "' width='10' height='10' fill='" + colour + "'/><text x='" + Num(kWidth - kRight + 18) +
         "' y='" + Num(kTop + 9 + 16.0 * k) + "' class='tick'>" + EscapeHtml(ser.name) + "</text>";
  }
  s += frame.Axes(options.x_label, options.y_label);
  body_ += s + CloseSvg();
  ++num_plots_;
}

void HtmlReport::AddVectorField(const std::string& title,
                                const std::vector<Eigen::Vector2d>& origins,
                                const std::vector<Eigen::Vector2d>& vectors, double scale,
                                double width, double height, const std::string& caption) {
  LASERCELL_CHECK(origins.size() == vectors.size(), "vector field needs one vector per origin");
  Range xr, yr;
  xr.Add(0);
  xr.Add(width);
  yr.Add(0);
  yr.Add(height);
  const Frame frame(xr, yr, true, true);
  std::string s = OpenSvg(title);
  const std::size_t stride = std::max<std::size_t>(1, origins.size() / 20000);
  for (std::size_t i = 0; i < origins.size(); i += stride) {
    const Eigen::Vector2d a = origins[i], b = origins[i] + scale * vectors[i];
    if (!a.allFinite() || !b.allFinite()) continue;
    s += "<line x1='" + Num(frame.X(a.x())) + "' y1='" + Num(frame.Y(a.y())) + "' x2='" +
         Num(frame.X(b.x())) + "' y2='" + Num(frame.Y(b.y())) +
         "' stroke='#d62728' stroke-width='1'/><circle cx='" + Num(frame.X(a.x())) + "' cy='" +
         Num(frame.Y(a.y())) + "' r='1' fill='#444'/>";
  }
  s += frame.Axes("column (px)", "row (px)");
  body_ += s + CloseSvg(caption);
  ++num_plots_;
}

void HtmlReport::AddHeatmap(const std::string& title, const Eigen::MatrixXd& values, double width,
                            double height, const std::string& value_label) {
  Range xr, yr, vr;
  xr.Add(0);
  xr.Add(width);
  yr.Add(0);
  yr.Add(height);
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) vr.Add(values(r, c));
  }
  vr.Finish();
  const Frame frame(xr, yr, true, true);
  std::string s = OpenSvg(title);
  const double cw = width / std::max<Eigen::Index>(1, values.cols());
  const double ch = height / std::max<Eigen::Index>(1, values.rows());
  for (Eigen::Index r = 0; r < values.rows(); ++r) {
    for (Eigen::Index c = 0; c < values.cols(); ++c) {
      const double v = values(r, c);
      if (!std::isfinite(v)) continue;
      const double x0 = frame.X(c * cw), x1 = frame.X((c + 1) * cw);
      const double y0 = frame.Y(r * ch), y1 = frame.Y((r + 1) * ch);
      s += "<rect x='" + Num(x0) + "' y='" + Num(y0) + "' width='" + Num(x1 - x0 + 0.3) +
           "' height='" + Num(y1 - y0 + 0.3) + "' fill='" + Colour((v - vr.lo) / (vr.hi - vr.lo)) +
           "'><title>" + Num(v) + "</title></rect>";
    }
  }
  // Colour bar to the right of the plot.
  const double bx = kLeft + frame.plot_width() + 15, bh = frame.plot_height();
  for (int i = 0; i < 50; ++i) {
    s += "<rect x='" + Num(bx) + "' y='" + Num(kTop + bh * (49 - i) / 50.0) +
         "' width='14' height='" + Num(bh / 50.0 + 0.3) + "' fill='" + Colour(i / 49.0) + "'/>";
  }
  s += "<text x='" + Num(bx + 18) + "' y='" + Num(kTop + 8) + "' class='tick'>" + Num(vr.hi) +
       "</text><text x='" + Num(bx + 18) + "' y='" + Num(kTop + bh) + "' class='tick'>" +
       Num(vr.lo) + "</text>";
  s += frame.Axes("column (px)", "row (px)");
  body_ += s + CloseSvg("colour: " + value_label);
  ++num_plots_;
}

void HtmlReport::Add3dView(const Scene3d& scene, const std::string& three_js_path) {
  body_ += Scene3dHtml(scene, num_views3d_);
  three_js_path_ = ThreeJsPath(three_js_path);
  ++num_views3d_;
}

std::string HtmlReport::Html() const {
  // Read first: a missing three.js is an error, not a page without its views.
  const std::string scripts3d = num_views3d_ > 0 ? Scene3dScripts(three_js_path_) : "";
  std::string page;
  page += "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'>\n<title>" +
          EscapeHtml(title_) + "</title>\n";
  // First script: record any later script error in the DOM, for headless checks.
  page +=
      "<script>window.addEventListener('error',function(e){var b=document.body;"
      "if(b){b.dataset.reportErrors=(b.dataset.reportErrors||'')+e.message+';';}});</script>\n";
  page +=
      "<style>body{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}"
      "table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #bbb;padding:2px 8px;"
      "text-align:right}th{background:#eee}table.kv th{text-align:left}"
      ".warning{color:#a00;font-weight:bold}svg .tick{font-size:11px;fill:#333}"
      "svg .label{font-size:12px;fill:#222}svg .title{font-size:14px;font-weight:bold}"
      "figure{margin:1em 0}figcaption{font-size:12px;color:#555}</style>\n";
  if (num_views3d_ > 0) page += Scene3dStyle();
  page += "</head>\n<body>\n<h1>" + EscapeHtml(title_) + "</h1>\n" + body_ + scripts3d;
  page +=
      "<script>document.body.dataset.plots=String(document.querySelectorAll('svg.lc-plot')."
      "length);document.body.dataset.reportReady='1';</script>\n</body></html>\n";
  return page;
}

void WriteHtmlReport(const std::string& path, const HtmlReport& report) {
  io::WriteFileAtomically(path, report.Html());
}

}  // namespace lasercell::report
