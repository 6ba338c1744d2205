#pragma once
// Self-contained HTML reports for calibrations and localizations: one file, no network, plots as
// inline SVG drawn here (no JavaScript library); 3D views drawn by an inlined three.js
// (core/html_scene3d.hpp). Every plot is an
// <svg class="lc-plot" data-plot="TITLE">; a small inline script marks the page
// <body data-report-ready="1" data-plots="N"> after load and records script errors in
// data-report-errors, so a headless browser test can check "page loads, no script errors, plots
// present" (tests/core/html_report_test.cpp does this with Debian's chromium).
//
// Units are whatever the caller says in the axis labels (px, mm, deg). Libraries fill a report
// with data; only tools write it (WriteHtmlReport is atomic).

#include <Eigen/Core>
#include <array>
#include <string>
#include <utility>
#include <vector>

namespace lasercell::report {

struct Scene3d;  // core/html_scene3d.hpp

/// `text` with & < > " ' replaced by HTML entities, safe in element text and quoted attributes.
std::string EscapeHtml(const std::string& text);

/// One named set of (x, y) points in a scatter/line plot.
struct Series {
  std::string name;       ///< Legend entry.
  std::vector<double> x;  ///< Same length as y.
  std::vector<double> y;
  bool lines = false;  ///< Connect the points in order (a line plot) instead of markers.
};

/// Axis and frame options of a 2-D plot.
struct PlotOptions {
  std::string x_label;        ///< With unit, e.g. "column (px)".
  std::string y_label;        ///< With unit.
  bool equal_aspect = false;  ///< Same scale on both axes (image plots).
  bool y_down = false;        ///< Image convention: y grows downwards.
  /// Fixed axis ranges [x0, x1, y0, y1]; all zero = from the data.
  std::array<double, 4> range = {0, 0, 0, 0};
};

class HtmlReport {
 public:
  explicit HtmlReport(std::string title);

  /// A new section heading (h2).
  void AddHeading(const std::string& text);
  /// A paragraph of plain text (HTML-escaped).
  void AddParagraph(const std::string& text);
  /// A highlighted warning line (e.g. "focal length poorly observed").
  void AddWarning(const std::string& text);
  /// A two-column table of named values.
  void AddKeyValues(const std::vector<std::pair<std::string, std::string>>& rows);
  /// A table with a header row; every row must have header.size() cells.
  void AddTable(const std::vector<std::string>& header,
                const std::vector<std::vector<std::string>>& rows);
  /// Histogram of `values` with `bins` equal bins over their range.
  void AddHistogram(const std::string& title, const std::vector<double>& values,
                    const std::string& x_label, int bins = 40);
  /// Bar chart, one bar per label (e.g. per-image RMS).
  void AddBars(const std::string& title, const std::vector<std::string>& labels,
               const std::vector<double>& values, const std::string& y_label);
  /// Scatter / line plot of one or more series.
  void AddScatter(const std::string& title, const std::vector<Series>& series,
                  const PlotOptions& options);
  /// Arrows from origins[i] to origins[i] + scale * vectors[i] in image coordinates
  /// (x right, y down) over a width x height frame, e.g. reprojection residuals magnified.
  void AddVectorField(const std::string& title, const std::vector<Eigen::Vector2d>& origins,
                      const std::vector<Eigen::Vector2d>& vectors, double scale, double width,
                      double height, const std::string& caption);
  /// Colour map of values(row, col) covering [0, width] x [0, height] (y down), with a colour
  /// bar labelled `value_label`. NaN cells are drawn empty.
  void AddHeatmap(const std::string& title, const Eigen::MatrixXd& values, double width,
                  double height, const std::string& value_label);

  /// An interactive 3D view of `scene` (core/html_scene3d.hpp); throws InputError when the scene
  /// fails Scene3d::Check. three.js is read from ThreeJsPath(three_js_path) when the page is
  /// made (the path of the last call wins), so Html and WriteHtmlReport throw FileError when
  /// libjs-three is missing rather than write a page without the view.
  void Add3dView(const Scene3d& scene, const std::string& three_js_path = "");

  /// Number of plots added so far.
  int NumPlots() const { return num_plots_; }
  /// Number of 3D views added so far.
  int NumViews3d() const { return num_views3d_; }
  /// The complete, self-contained page.
  std::string Html() const;

 private:
  std::string title_;
  std::string body_;
  int num_plots_ = 0;
  int num_views3d_ = 0;
  std::string three_js_path_;  // resolved by the last Add3dView
};

/// Writes the report atomically (temp file + rename); throws FileError when it cannot.
void WriteHtmlReport(const std::string& path, const HtmlReport& report);

}  // namespace lasercell::report
