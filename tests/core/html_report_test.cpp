#include "core/html_report.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::report {
namespace {

HtmlReport FullReport() {
  HtmlReport report("Test <report> & more");
  report.AddHeading("Summary");
  report.AddKeyValues({{"rms_px", "0.12"}, {"images", "14"}});
  report.AddWarning("focal length poorly observed");
  report.AddTable({"image", "rms (px)"}, {{"a.png", "0.1"}, {"b.png", "0.2"}});
  report.AddHistogram("Residuals", {0.1, -0.2, 0.05, 0.3, -0.1}, "residual (px)", 10);
  report.AddBars("Per-image RMS", {"a", "b", "c"}, {0.1, 0.2, 0.15}, "RMS (px)");
  report.AddScatter("Line",
                    {{"fit", {0, 1, 2}, {0, 1, 4}, true}, {"data", {0, 1, 2}, {0.1, 0.9, 4.1}}},
                    {"x (mm)", "y (mm)"});
  report.AddVectorField("Residual vectors", {{10, 10}, {500, 300}}, {{0.1, 0.2}, {-0.3, 0.1}},
                        100.0, 640, 480, "x100");
  Eigen::MatrixXd grid(3, 4);
  grid << 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, std::nan("");
  report.AddHeatmap("Uncertainty", grid, 640, 480, "1-sigma (px)");
  return report;
}

TEST(HtmlReport, CountsPlotsAndEscapesText) {
  const HtmlReport report = FullReport();
  EXPECT_EQ(report.NumPlots(), 5);
  const std::string html = report.Html();
  EXPECT_NE(html.find("Test &lt;report&gt; &amp; more"), std::string::npos);
  EXPECT_EQ(html.find("<report>"), std::string::npos);
  std::size_t svgs = 0;
  for (std::size_t p = html.find("class='lc-plot'"); p != std::string::npos;
       p = html.find("class='lc-plot'", p + 1)) {
    ++svgs;
  }
  EXPECT_EQ(svgs, 5u);
  // Self-contained: nothing is fetched from the network.
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));
  EXPECT_EQ(html.find("https://"), std::string::npos);
}

TEST(HtmlReport, RejectsRaggedTables) {
  HtmlReport report("t");
  EXPECT_THROW(report.AddTable({"a", "b"}, {{"1"}}), InternalError);
}

using test::HeadlessChromiumDom;

TEST(HtmlReport, LoadsInHeadlessChromiumWithPlotsAndNoScriptErrors) {
  const test::TestDir dir("report");
  const std::string path = dir.File("report.html");
  WriteHtmlReport(path, FullReport());
  const std::string dom = HeadlessChromiumDom(path);
  ASSERT_FALSE(dom.empty()) << "chromium did not run (scripts/install-deps installs it)";
  EXPECT_NE(dom.find("data-report-ready=\"1\""), std::string::npos) << dom.substr(0, 400);
  EXPECT_NE(dom.find("data-plots=\"5\""), std::string::npos);
  EXPECT_EQ(dom.find("data-report-errors"), std::string::npos);
}

TEST(HtmlReport, HeadlessCheckDetectsAScriptError) {
  // The check above must be able to fail: a page whose script throws is reported.
  std::string html = FullReport().Html();
  html.insert(html.find("</body>"), "<script>undefinedFunction();</script>");
  const test::TestDir dir("report_error");
  const std::string path = dir.File("report.html");
  io::WriteFileAtomically(path, html);
  const std::string dom = HeadlessChromiumDom(path);
  ASSERT_FALSE(dom.empty());
  EXPECT_NE(dom.find("data-report-errors"), std::string::npos);
}

}  // namespace
}  // namespace lasercell::report
