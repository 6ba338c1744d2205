#include "core/html_scene3d.hpp"

#include <gtest/gtest.h>
#include <stdlib.h>  // setenv, unsetenv (POSIX)

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <regex>
#include <string>

#include "core/error.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::report {
namespace {

constexpr const char* kThreeJs = "/usr/share/javascript/three/three.min.js";
// The view's clear colour (kViewScript's BACKGROUND) and the cube's colour in the test scene.
constexpr int kBackground[3] = {0xf2, 0xf3, 0xf5};
constexpr std::array<float, 3> kCubeRgb = {0.8f, 0.4f, 0.0f};

// Base64 decoding written independently of the encoder under test (RFC 4648 alphabet).
std::string DecodeBase64(const std::string& text) {
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  int bits = 0, buffer = 0;
  for (char c : text) {
    if (c == '=') break;
    const std::size_t v = alphabet.find(c);
    EXPECT_NE(v, std::string::npos) << "not base64: " << c;
    buffer = (buffer << 6) | static_cast<int>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((buffer >> bits) & 0xff);
    }
  }
  return out;
}

// Little-endian float32 values from bytes, assembled byte by byte.
std::vector<float> FloatsFromLittleEndian(const std::string& bytes) {
  std::vector<float> out(bytes.size() / 4);
  for (std::size_t i = 0; i < out.size(); ++i) {
    std::uint32_t u = 0;
    for (int k = 3; k >= 0; --k) u = (u << 8) | static_cast<std::uint8_t>(bytes[4 * i + k]);
    std::memcpy(&out[i], &u, 4);
  }
  return out;
}

// The JSON data of view `index` in a page.
nlohmann::json ViewData(const std::string& html, int index) {
  const std::string open =
      "<script type='application/json' id='lc-view3d-" + std::to_string(index) + "-data'>";
  const std::size_t begin = html.find(open);
  if (begin == std::string::npos) return {};
  const std::size_t end = html.find("</script>", begin);
  return nlohmann::json::parse(html.substr(begin + open.size(), end - begin - open.size()));
}

Scene3dMesh Cube(double side, const Eigen::Isometry3d& world_from_mesh) {
  Scene3dMesh cube;
  cube.name = "part <cube>";
  const float h = static_cast<float>(side / 2);
  for (int i = 0; i < 8; ++i)
    cube.vertices.emplace_back(i & 1 ? h : -h, i & 2 ? h : -h, i & 4 ? h : -h);
  // Two triangles per face, corners indexed by their (x, y, z) bits.
  cube.faces = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  cube.world_from_mesh = world_from_mesh;
  cube.rgb = kCubeRgb;
  return cube;
}

// A table top of points, a posed cube on it, its frame and a region of interest around both.
Scene3d TestScene(std::size_t points = 40000) {
  Scene3d scene;
  scene.title = "Localization";
  Scene3dPoints sweep;
  sweep.name = "sweep";
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-100.0f, 100.0f);
  for (std::size_t i = 0; i < points; ++i)
    sweep.positions.push_back(Eigen::Vector3f{u(rng), u(rng), 0.0f});
  sweep.size_mm = 1.5f;
  scene.points.push_back(sweep);
  Eigen::Isometry3d base_from_part = Eigen::Isometry3d::Identity();
  base_from_part.rotate(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  base_from_part.translation() = Eigen::Vector3d(10, -5, 30);
  scene.meshes.push_back(Cube(60, base_from_part));
  // A grasp frame on the top face, z down into the part as a gripper approaches it.
  Eigen::Isometry3d part_from_grasp = Eigen::Isometry3d::Identity();
  part_from_grasp.rotate(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  part_from_grasp.translation() = Eigen::Vector3d(0, 0, 30);
  scene.frames.push_back({"grasp 1", base_from_part * part_from_grasp, 60.0f});
  Scene3dBox roi;
  roi.name = "roi";
  roi.min_mm = Eigen::Vector3d(-110, -110, -5);
  roi.max_mm = Eigen::Vector3d(110, 110, 80);
  scene.boxes.push_back(roi);
  return scene;
}

// A report with a table and a plot around the view, as the localization report has.
HtmlReport TestReport(const Scene3d& scene, const std::string& three_js_path = kThreeJs) {
  HtmlReport report("Localization report");
  report.AddKeyValues({{"parts found", "1"}});
  report.Add3dView(scene, three_js_path);
  report.AddHistogram("Residuals", {0.1, -0.2, 0.05, 0.3}, "residual (mm)", 5);
  return report;
}

std::string Attribute(const std::string& dom, const std::string& name) {
  const std::regex re(name + "=\"([^\"]*)\"");
  std::smatch m;
  return std::regex_search(dom, m, re) ? m[1].str() : std::string("(absent)");
}

TEST(Scene3d, DecimatesToExactlyMaxPointsWithAUniformStride) {
  constexpr std::size_t kN = 1000003, kMax = 200000;
  std::vector<Eigen::Vector3f> positions;
  for (std::size_t i = 0; i < kN; ++i) positions.emplace_back(static_cast<float>(i), 0.0f, 1.0f);
  const std::vector<Eigen::Vector3f> kept = DecimatePoints(positions, kMax);
  ASSERT_EQ(kept.size(), kMax);
  std::size_t largest_gap = 0;
  for (std::size_t i = 0; i < kMax; ++i) {
    const auto index = static_cast<std::size_t>(kept[i].x());
    ASSERT_EQ(index, i * kN / kMax) << i;  // the documented indices (no overflow at this size)
    if (i > 0)
      largest_gap = std::max(largest_gap, index - static_cast<std::size_t>(kept[i - 1].x()));
  }
  EXPECT_LE(largest_gap, kN / kMax + 1);
  EXPECT_EQ(DecimatePoints(positions, kMax), kept);  // deterministic
  EXPECT_EQ(DecimatePoints(positions, kN).size(), kN);
  EXPECT_EQ(DecimatePoints(positions, kN + 5).size(), kN);
}

TEST(Scene3d, PayloadDecodesBackToTheInputFloats) {
  Scene3d scene = TestScene(1001);
  scene.points[0].max_points = 250;
  scene.points[0].positions[0] = Eigen::Vector3f(1e-7f, -32.51f, 0.1f);  // not round in binary
  const std::string html = TestReport(scene).Html();
  const nlohmann::json data = ViewData(html, 0);
  ASSERT_TRUE(data.is_object()) << "no view data in the page";

  const std::vector<Eigen::Vector3f> kept = DecimatePoints(scene.points[0].positions, 250);
  const std::vector<float> positions =
      FloatsFromLittleEndian(DecodeBase64(data["points"][0]["positions"].get<std::string>()));
  ASSERT_EQ(positions.size(), 3 * kept.size());
  EXPECT_EQ(data["points"][0]["count"].get<std::size_t>(), 250u);
  EXPECT_EQ(data["points"][0]["total"].get<std::size_t>(), 1001u);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_EQ(positions[3 * i + k], kept[i][k]) << i;  // bit exact
  }
  const Scene3dMesh& cube = scene.meshes[0];
  const std::vector<float> vertices =
      FloatsFromLittleEndian(DecodeBase64(data["meshes"][0]["vertices"].get<std::string>()));
  ASSERT_EQ(vertices.size(), 3 * cube.vertices.size());
  for (std::size_t i = 0; i < cube.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_EQ(vertices[3 * i + k], cube.vertices[i][k]);
  }
  const std::string faces = DecodeBase64(data["meshes"][0]["faces"].get<std::string>());
  ASSERT_EQ(faces.size(), 4 * 3 * cube.faces.size());
  for (std::size_t i = 0; i < 3 * cube.faces.size(); ++i) {
    std::uint32_t v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<std::uint8_t>(faces[4 * i + k]);
    EXPECT_EQ(v, static_cast<std::uint32_t>(cube.faces[i / 3][static_cast<int>(i % 3)]));
  }
  // Poses as column-major 4x4 (three.js Matrix4.fromArray).
  const std::vector<double> m = data["meshes"][0]["matrix"].get<std::vector<double>>();
  ASSERT_EQ(m.size(), 16u);
  EXPECT_EQ(m[12], 10.0);
  EXPECT_EQ(m[14], 30.0);
  EXPECT_DOUBLE_EQ(m[1], std::sin(0.4));  // R(1, 0)
  // The camera is framed on everything: the box corners are the outermost points here.
  const std::vector<double> center = data["center"].get<std::vector<double>>();
  EXPECT_NEAR(center[2], 37.5, 1e-9);
  EXPECT_NEAR(data["radius"].get<double>(), 0.5 * std::sqrt(220.0 * 220 * 2 + 85.0 * 85), 1e-6);
  // Base64 padding cases of the encoder itself.
  EXPECT_EQ(Base64("M"), "TQ==");
  EXPECT_EQ(Base64("Ma"), "TWE=");
  EXPECT_EQ(Base64("Man"), "TWFu");
}

TEST(Scene3d, PageInlinesThreeJsAndFetchesNothing) {
  const Scene3d scene = TestScene(200000);
  const std::string html = TestReport(scene).Html();
  const std::string three = io::ReadFileBytes(kThreeJs);
  const std::string controls = io::ReadFileBytes(OrbitControlsPath(kThreeJs));
  ASSERT_NE(html.find(three), std::string::npos) << "three.min.js is not inlined verbatim";
  ASSERT_NE(html.find(controls), std::string::npos) << "OrbitControls.js is not inlined verbatim";
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("file://"), std::string::npos);
  // The libraries' comments name their authors' web sites; outside them no URL is left except
  // the SVG namespace of the histogram.
  std::string ours = html;
  ours.erase(ours.find(three), three.size());
  ours.erase(ours.find(controls), controls.size());
  EXPECT_EQ(ours.find("http://"), ours.find("http://www.w3.org/2000/svg"));
  EXPECT_EQ(ours.find("http://", ours.find("http://www.w3.org/2000/svg") + 1), std::string::npos);
  EXPECT_EQ(ours.find("https://"), std::string::npos);
  // A second view reuses the inlined libraries.
  HtmlReport two = TestReport(TestScene(10));
  two.Add3dView(TestScene(10), kThreeJs);
  const std::string html2 = two.Html();
  EXPECT_EQ(html2.find(three, html2.find(three) + three.size()), std::string::npos);
  EXPECT_NE(html2.find("id='lc-view3d-1'"), std::string::npos);
  // 200000 points of 12 bytes in base64 (x 4/3) plus the libraries: a few MB.
  RecordProperty("page_bytes_200k_points", std::to_string(html.size()));
  EXPECT_LT(html.size(), 3200000u + three.size() + controls.size() + 100000u);
  EXPECT_GT(html.size(), 3200000u);
}

TEST(Scene3d, MissingThreeJsIsAFileErrorNamingThePath) {
  const std::string missing = "/nonexistent/three/three.min.js";
  const HtmlReport report = TestReport(TestScene(10), missing);
  try {
    (void)report.Html();
    FAIL() << "no FileError for a missing three.js";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), missing);
    EXPECT_NE(std::string(e.what()).find("install libjs-three"), std::string::npos) << e.what();
  }
  const test::TestDir dir("scene3d_missing");
  EXPECT_THROW(WriteHtmlReport(dir.File("report.html"), report), FileError);
  EXPECT_EQ(dir.Entries(), 0u) << "a page without its 3D view was written";

  // The environment variable overrides the default path; an explicit argument overrides both.
  ::setenv("LASERCELL_THREE_JS", missing.c_str(), 1);
  EXPECT_EQ(ThreeJsPath(), missing);
  EXPECT_EQ(ThreeJsPath(kThreeJs), kThreeJs);
  HtmlReport from_env("env");
  from_env.Add3dView(TestScene(10));
  EXPECT_THROW((void)from_env.Html(), FileError);
  ::unsetenv("LASERCELL_THREE_JS");
  EXPECT_EQ(ThreeJsPath(), kThreeJs);

  // A file that is not three.js, and three.js without OrbitControls next to it.
  const std::string not_three = dir.File("three.min.js");
  test::Spit(not_three, "console.log('hello');");
  EXPECT_THROW((void)TestReport(TestScene(10), not_three).Html(), FileError);
  std::filesystem::copy_file(kThreeJs, not_three,
                             std::filesystem::copy_options::overwrite_existing);
  try {
    (void)TestReport(TestScene(10), not_three).Html();
    FAIL() << "no FileError without OrbitControls.js";
  } catch (const FileError& e) {
    EXPECT_EQ(e.path(), OrbitControlsPath(not_three));
  }
}

TEST(Scene3d, RejectsBadObjectsNamingThem) {
  Scene3d bad_face = TestScene(10);
  bad_face.meshes[0].faces.push_back({0, 1, 8});
  HtmlReport report("r");
  try {
    report.Add3dView(bad_face, kThreeJs);
    FAIL() << "no InputError for a face index out of range";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("mesh 'part <cube>'.faces[12]"), std::string::npos)
        << e.what();
  }
  Scene3d bad_box = TestScene(10);
  bad_box.boxes[0].min_mm.x() = 200;
  EXPECT_THROW(report.Add3dView(bad_box, kThreeJs), InputError);
  Scene3d bad_point = TestScene(10);
  bad_point.points[0].positions[3].y() = std::nanf("");
  EXPECT_THROW(report.Add3dView(bad_point, kThreeJs), InputError);
  Scene3d bad_opacity = TestScene(10);
  bad_opacity.meshes[0].opacity = 0.0f;
  EXPECT_THROW(report.Add3dView(bad_opacity, kThreeJs), InputError);
  EXPECT_EQ(report.NumViews3d(), 0);
}

// Counts, inside the canvas rectangle, the pixels that differ from the background, the pixels
// of the cube's colour (any shade: the lights scale all channels alike) and those of the x axis.
struct PixelCounts {
  int area = 0, drawn = 0, cube = 0, x_axis = 0;
};
PixelCounts CountPixels(const cv::Mat& bgr, int x0, int y0, int w, int h) {
  PixelCounts c;
  for (int y = std::max(0, y0); y < std::min(bgr.rows, y0 + h); ++y) {
    for (int x = std::max(0, x0); x < std::min(bgr.cols, x0 + w); ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      const int r = p[2], g = p[1], b = p[0];
      ++c.area;
      if (std::abs(r - kBackground[0]) + std::abs(g - kBackground[1]) +
              std::abs(b - kBackground[2]) >
          30) {
        ++c.drawn;
      }
      const double ratio = kCubeRgb[1] / kCubeRgb[0];
      if (r >= 60 && std::abs(g - ratio * r) <= 0.06 * r + 2 && b <= 0.06 * r + 2) ++c.cube;
      // The frame's x axis is drawn unlit in #d62728.
      if (std::abs(r - 0xd6) + std::abs(g - 0x27) + std::abs(b - 0x28) <= 12) ++c.x_axis;
    }
  }
  return c;
}

TEST(Scene3d, DrawsInHeadlessChromiumWithWebGL) {
  const test::TestDir dir("scene3d_webgl");
  const std::string page = dir.File("report.html"), png = dir.File("screenshot.png");
  WriteHtmlReport(page, TestReport(TestScene()));
  const std::string dom = test::HeadlessChromium(
      page,
      "--use-angle=swiftshader --enable-unsafe-swiftshader --window-size=1000,800 "
      "--screenshot='" +
          png + "'");
  ASSERT_FALSE(dom.empty()) << "chromium did not run (scripts/install-deps installs it)";
  EXPECT_EQ(Attribute(dom, "data-report-errors"), "(absent)");
  EXPECT_EQ(Attribute(dom, "data-report-ready"), "1");
  EXPECT_EQ(Attribute(dom, "data-plots"), "1");
  EXPECT_EQ(Attribute(dom, "data-view3d"), "1");
  ASSERT_EQ(Attribute(dom, "data-view3d-drawn"), "1") << dom.substr(0, 2000);
  EXPECT_EQ(Attribute(dom, "data-view3d-objects"), "4");
  int x = 0, y = 0, w = 0, h = 0;
  ASSERT_EQ(std::sscanf(Attribute(dom, "data-view3d-rect").c_str(), "%d,%d,%d,%d", &x, &y, &w, &h),
            4);
  const cv::Mat shot = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(shot.empty()) << "no screenshot at " << png;
  const PixelCounts c = CountPixels(shot, x, y, w, h);
  ASSERT_GT(c.area, 100000) << "the canvas is not inside the window: " << x << "," << y;
  // Measured: the objects cover ~13 % of the canvas, the cube ~3 %; the legend's swatch of the
  // cube's colour is 100 px (0.02 %).
  EXPECT_GT(c.drawn, c.area / 20) << c.drawn << " of " << c.area;
  EXPECT_GT(c.cube, c.area / 100) << c.cube << " of " << c.area;
  RecordProperty("canvas_px", c.area);
  RecordProperty("drawn_px", c.drawn);
  EXPECT_GT(c.x_axis, 100) << "the grasp frame's x axis is not drawn";
  RecordProperty("cube_px", c.cube);
  RecordProperty("x_axis_px", c.x_axis);
}

TEST(Scene3d, ShowsANoticeWithoutWebGL) {
  const test::TestDir dir("scene3d_nowebgl");
  const std::string page = dir.File("report.html");
  WriteHtmlReport(page, TestReport(TestScene(1000)));
  const std::string dom = test::HeadlessChromium(page, "--disable-gpu --disable-3d-apis");
  ASSERT_FALSE(dom.empty()) << "chromium did not run (scripts/install-deps installs it)";
  EXPECT_EQ(Attribute(dom, "data-report-errors"), "(absent)");
  EXPECT_EQ(Attribute(dom, "data-report-ready"), "1");
  EXPECT_EQ(Attribute(dom, "data-plots"), "1");  // the rest of the page is there
  EXPECT_NE(dom.find("parts found"), std::string::npos);
  EXPECT_EQ(Attribute(dom, "data-view3d-webgl"), "0");
  EXPECT_EQ(Attribute(dom, "data-view3d-drawn"), "(absent)");
  EXPECT_NE(dom.find("3D view not shown: this browser provides no WebGL."), std::string::npos);
}

}  // namespace
}  // namespace lasercell::report
