// `lasercell calibrate laser --camera CAMERA.cameramodel (--planes DIR --heights-mm H1,H2,... |
//  --stripe-images 'GLOB' --board chessboard:COLSxROWS:SQUARE_MM) --cell CELL.yaml
//  --report LASER.html --json LASER.json`: the laser plane in the sensor frame (calib/laser_plane.hpp),
// written as the `laser` plane of CELL.yaml (only that entry changes; the file is created when
// missing), a versioned JSON summary and a self-contained HTML report.
#include <glob.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "calib/camera_model.hpp"
#include "calib/laser_plane.hpp"
#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"
#include "tools/commands.hpp"
#include "triangulation/profile_io.hpp"

namespace lasercell::tools {
namespace {

struct LaserArgs {
  std::string camera, planes, heights, stripe_glob, board, cell, report, json;
  std::string plate_normal = "0,0,-1";
  double plate_distance_mm = std::nan("");
  std::string laser_color = "green";
  bool quiet = false;
  bool fixed_plate_normal = false;
};

std::vector<double> ParseList(const std::string& text, const std::string& what, std::size_t count = 0) {
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v)) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      throw OptionError(what + " is '" + text + "'; expected comma-separated numbers");
    }
  }
  if (values.empty() || (count > 0 && values.size() != count)) {
    throw OptionError(what + " is '" + text + "'; expected " +
                      (count > 0 ? std::to_string(count) : std::string("one or more")) +
                      " comma-separated numbers");
  }
  return values;
}

std::string NowUtc() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

/// FNV-1a 64 over the input files' bytes, as provenance.
struct Digest {
  std::uint64_t h = 1469598103934665603ull;
  void Add(const std::string& bytes) {
    for (const char c : bytes) {
      h ^= static_cast<unsigned char>(c);
      h *= 1099511628211ull;
    }
  }
  std::string Text() const {
    char buf[40];
    std::snprintf(buf, sizeof buf, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
    return buf;
  }
};

/// profiles/plane_<i>.lcp files of DIR (or DIR/profiles), ordered by i.
std::vector<std::string> PlaneFiles(const std::string& dir) {
  std::map<long, std::string> files;
  const std::regex pattern("plane_([0-9]+)\\.lcp");
  for (const std::string& d : {dir, dir + "/profiles"}) {
    std::error_code ec;
    if (!std::filesystem::is_directory(d, ec)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(d, ec)) {
      std::smatch match;
      const std::string name = entry.path().filename().string();
      if (std::regex_match(name, match, pattern)) files[std::stol(match[1])] = entry.path().string();
    }
    if (!files.empty()) break;
  }
  if (files.empty()) {
    throw FileError(dir, "holds no plane_<i>.lcp profile files (nor does its profiles/ folder); "
                         "pass the folder of the white-plane sweeps");
  }
  std::vector<std::string> out;
  for (auto& [i, path] : files) out.push_back(path);
  return out;
}

std::vector<std::string> Glob(const std::string& pattern) {
  glob_t g{};
  std::vector<std::string> out;
  if (::glob(pattern.c_str(), 0, nullptr, &g) == 0) {
    for (std::size_t i = 0; i < g.gl_pathc; ++i) out.emplace_back(g.gl_pathv[i]);
  }
  globfree(&g);
  std::sort(out.begin(), out.end());
  if (out.empty()) throw OptionError("--stripe-images '" + pattern + "' matches no file");
  return out;
}

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json ResultJson(const calib::LaserPlaneResult& r, const std::string& camera) {
  nlohmann::json j;
  j["format"] = "lasercell.laser_plane";
  j["version"] = 1;
  j["method"] = r.method;
  j["frame"] = "sensor";
  j["camera"] = camera;
  j["plane"] = {{"normal", {r.normal.x(), r.normal.y(), r.normal.z()}},
                {"offset_mm", r.offset_mm},
                {"point_mm", {r.point_mm.x(), r.point_mm.y(), r.point_mm.z()}},
                {"equation", "normal . p + offset_mm = 0, p in the sensor frame (mm)"}};
  nlohmann::json cov = nlohmann::json::array();
  for (int a = 0; a < 4; ++a) {
    nlohmann::json row = nlohmann::json::array();
    for (int b = 0; b < 4; ++b) row.push_back(Number(r.covariance(a, b)));
    cov.push_back(row);
  }
  j["covariance_n_d"] = cov;
  j["normal_sigma_deg"] = Number(r.normal_sigma_deg);
  j["offset_sigma_mm"] = Number(r.offset_sigma_mm);
  j["rms_mm"] = Number(r.rms_mm);
  if (r.method == "heights") j["rms_px"] = Number(r.rms_px);
  j["points"] = r.points;
  j["converged"] = r.converged;
  j["iterations"] = r.iterations;
  j["median_triangulation_angle_deg"] = Number(r.median_triangulation_angle_deg);
  j["ill_conditioned"] = r.ill_conditioned;
  if (r.zero_distance_mm) {
    j["plate_zero_distance_mm"] = Number(*r.zero_distance_mm);
    j["plate_zero_distance_sigma_mm"] = Number(r.zero_distance_sigma_mm);
    j["plate_tilt_deg"] = Number(r.plate_tilt_deg);
    j["plate_tilt_sigma_deg"] = Number(r.plate_tilt_sigma_deg);
  }
  j["leave_one_out"] = {{"max_normal_change_deg", Number(r.loo_max_normal_change_deg)},
                        {"max_offset_change_mm", Number(r.loo_max_offset_change_mm)}};
  nlohmann::json items = nlohmann::json::array();
  for (const auto& it : r.items) {
    nlohmann::json e = {{"name", it.name},   {"used", it.used},     {"note", it.note},
                        {"points", it.points}, {"rms_mm", Number(it.rms_mm)}};
    if (r.method == "heights") {
      e["height_mm"] = it.height_mm;
      e["rms_px"] = Number(it.rms_px);
    } else {
      e["corner_reprojection_rms_px"] = Number(it.reprojection_rms_px);
      e["scan"] = it.scan_along_rows ? "rows" : "columns";
    }
    e["leave_one_out"] = {{"normal_change_deg", Number(it.loo_normal_change_deg)},
                          {"offset_change_mm", Number(it.loo_offset_change_mm)},
                          {"max_displacement_mm", Number(it.loo_max_displacement_mm)}};
    if (r.method == "heights") e["leave_one_out"]["plate_distance_held"] = it.loo_zero_distance_held;
    items.push_back(e);
  }
  j[r.method == "heights" ? "heights" : "images"] = items;
  j["warnings"] = r.warnings;
  return j;
}

std::string Fmt(double v, int precision = 4) {
  if (!std::isfinite(v)) return "n/a";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*g", precision, v);
  return buf;
}

report::HtmlReport MakeReport(const calib::LaserPlaneResult& r, const calib::CameraModel& camera) {
  report::HtmlReport page("Laser plane calibration (" + r.method + ")");
  page.AddHeading("Result");
  for (const auto& w : r.warnings) page.AddWarning(w);
  page.AddKeyValues({
      {"method", r.method == "heights" ? "white plane at known heights" : "laser stripe on a chessboard (Zhou & Zhang 2005)"},
      {"plane (sensor frame)", "n = [" + Fmt(r.normal.x(), 9) + ", " + Fmt(r.normal.y(), 9) + ", " +
                                   Fmt(r.normal.z(), 9) + "], d = " + Fmt(r.offset_mm, 9) + " mm"},
      {"p0 (nearest the sensor origin)", "[" + Fmt(r.point_mm.x(), 7) + ", " + Fmt(r.point_mm.y(), 7) + ", " + Fmt(r.point_mm.z(), 7) + "] mm"},
      {"1 sigma normal / offset", Fmt(r.normal_sigma_deg, 3) + " deg / " + Fmt(r.offset_sigma_mm, 3) + " mm"},
      {"RMS residual", Fmt(r.rms_mm, 4) + " mm" + (r.method == "heights" ? " (" + Fmt(r.rms_px, 3) + " px of peak row)" : "")},
      {"points", std::to_string(r.points)},
      {"median ray-to-plane angle", Fmt(r.median_triangulation_angle_deg, 4) + " deg"},
      {"leave-one-out: max normal / offset change",
       Fmt(r.loo_max_normal_change_deg, 3) + " deg / " + Fmt(r.loo_max_offset_change_mm, 3) + " mm"},
      {"converged", r.converged ? "yes (" + std::to_string(r.iterations) + " iterations)" : "NO: " + r.termination},
  });
  if (r.zero_distance_mm) {
    page.AddParagraph("Distance from the sensor origin to the height-0 plate: " +
                      Fmt(*r.zero_distance_mm, 8) + " mm (1 sigma " + Fmt(r.zero_distance_sigma_mm, 3) +
                      " mm). Plate normal tilted from the given one towards the laser line by " +
                      Fmt(r.plate_tilt_deg, 4) + " deg (1 sigma " + Fmt(r.plate_tilt_sigma_deg, 3) + " deg).");
  }
  const bool heights = r.method == "heights";
  page.AddHeading(heights ? "Per height" : "Per image");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> labels;
  std::vector<double> rms;
  for (const auto& it : r.items) {
    rows.push_back({it.name, it.used ? "yes" : "no", heights ? Fmt(it.height_mm) : Fmt(it.reprojection_rms_px, 3),
                    std::to_string(it.points), Fmt(it.rms_mm, 4), Fmt(it.loo_normal_change_deg, 3),
                    Fmt(it.loo_offset_change_mm, 3), Fmt(it.loo_max_displacement_mm, 3), it.note});
    if (it.used) {
      labels.push_back(std::filesystem::path(it.name).filename().string());
      rms.push_back(it.rms_mm);
    }
  }
  page.AddTable({heights ? "capture" : "image", "used", heights ? "height (mm)" : "corner RMS (px)", "points",
                 "RMS (mm)", "LOO normal change (deg)", "LOO d change (mm)", "LOO max displacement (mm)", "note"},
                rows);
  page.AddBars(heights ? "RMS residual per height" : "RMS residual per image", labels, rms, "RMS (mm)");
  page.AddHeading("Residuals");
  std::vector<double> values;
  std::map<int, report::Series> by_item, coverage;
  for (const auto& res : r.residuals) {
    values.push_back(res.residual_mm);
    auto& s = by_item[res.item];
    s.name = std::filesystem::path(r.items[static_cast<std::size_t>(res.item)].name).filename().string();
    s.x.push_back(heights ? res.pixel.x() : (r.items[static_cast<std::size_t>(res.item)].scan_along_rows ? res.pixel.y() : res.pixel.x()));
    s.y.push_back(res.residual_mm);
    auto& c = coverage[res.item];
    c.name = s.name;
    c.x.push_back(res.pixel.x());
    c.y.push_back(res.pixel.y());
  }
  page.AddHistogram("Laser-plane residuals", values, "signed distance from the plane (mm)");
  std::vector<report::Series> along, cover;
  for (auto& [k, s] : by_item) along.push_back(s);
  for (auto& [k, s] : coverage) cover.push_back(s);
  report::PlotOptions along_options;
  along_options.x_label = heights ? "image column (px)" : "position along the stripe: column, or row for vertical stripes (px)";
  along_options.y_label = "residual (mm)";
  page.AddScatter("Residual along the laser line", along, along_options);
  report::PlotOptions cover_options;
  cover_options.x_label = "column (px)";
  cover_options.y_label = "row (px)";
  cover_options.equal_aspect = true;
  cover_options.y_down = true;
  cover_options.range = {0, static_cast<double>(camera.width_px() - 1), 0, static_cast<double>(camera.height_px() - 1)};
  page.AddScatter("Stripe coverage of the image", cover, cover_options);
  return page;
}

void Run(const LaserArgs& args) {
  const bool by_planes = !args.planes.empty();
  if (by_planes == !args.stripe_glob.empty()) {
    throw OptionError("give either --planes DIR --heights-mm H1,H2,... or --stripe-images 'GLOB' --board ...");
  }
  Digest digest;
  digest.Add(io::ReadFileBytes(args.camera));
  const calib::CameraModel camera = calib::LoadCameraModel(args.camera);
  calib::LaserPlaneResult result;
  if (by_planes) {
    if (args.heights.empty()) throw OptionError("--planes needs --heights-mm H1,H2,... (one per plane_<i>.lcp)");
    const std::vector<std::string> files = PlaneFiles(args.planes);
    const std::vector<double> heights = ParseList(args.heights, "--heights-mm", files.size());
    calib::HeightPlaneOptions options;
    const auto m = ParseList(args.plate_normal, "--plate-normal", 3);
    options.plate_normal_in_sensor = Eigen::Vector3d(m[0], m[1], m[2]);
    if (std::isfinite(args.plate_distance_mm)) options.zero_distance_mm = args.plate_distance_mm;
    options.estimate_plate_tilt = !args.fixed_plate_normal;
    std::vector<calib::HeightCapture> captures;
    for (std::size_t i = 0; i < files.size(); ++i) {
      const std::string bytes = io::ReadFileBytes(files[i]);
      digest.Add(bytes);
      const triangulation::ProfileSet set = triangulation::DecodeProfiles(bytes, files[i]);
      if (static_cast<int>(set.header.image_width) != camera.width_px() ||
          static_cast<int>(set.header.image_height) != camera.height_px()) {
        throw FileError(files[i], "was recorded with a " + std::to_string(set.header.image_width) + "x" +
                                      std::to_string(set.header.image_height) + " sensor but the camera model is " +
                                      std::to_string(camera.width_px()) + "x" + std::to_string(camera.height_px()));
      }
      calib::HeightCapture c;
      c.name = files[i];
      c.height_mm = heights[i];
      for (const auto& p : set.profiles) {
        for (std::size_t j = 0; j < p.row_px.size(); ++j) {
          if (std::isfinite(p.row_px[j])) {
            c.peaks_px.emplace_back(static_cast<double>(set.header.first_column + j), p.row_px[j]);
          }
        }
      }
      captures.push_back(std::move(c));
    }
    result = calib::CalibrateLaserPlaneFromHeights(camera, captures, options);
  } else {
    if (args.board.empty()) throw OptionError("--stripe-images needs --board chessboard:COLSxROWS:SQUARE_MM");
    const calib::ChessboardSpec board = calib::ParseChessboardSpec(args.board);
    calib::StripeOptions options;
    options.laser_color = args.laser_color;
    std::vector<calib::StripeImage> images;
    for (const std::string& path : Glob(args.stripe_glob)) {
      const std::string bytes = io::ReadFileBytes(path);
      digest.Add(bytes);
      images.push_back(calib::DecodeStripeImage(bytes, path));
    }
    result = calib::CalibrateLaserPlaneFromStripes(camera, images, board, options);
  }
  // Outputs: the JSON and the report always (they explain a failure), the cell only for a
  // usable plane.
  if (!args.json.empty()) io::WriteFileAtomically(args.json, ResultJson(result, args.camera).dump(2) + "\n");
  if (!args.report.empty()) report::WriteHtmlReport(args.report, MakeReport(result, camera));
  if (result.ill_conditioned || !result.converged) {
    throw InputError("laser plane not written to " + args.cell + ": " +
                     (result.warnings.empty() ? result.Summary() : result.warnings.front()));
  }
  FrameGraph graph;
  std::error_code ec;
  if (std::filesystem::exists(args.cell, ec)) graph = LoadFrameGraph(args.cell);
  LaserPlaneEntry entry;
  entry.frame = "sensor";
  entry.normal = result.normal;
  entry.point_mm = result.point_mm;
  entry.covariance = result.covariance;
  entry.provenance.tool = std::string("lasercell calibrate laser ") + LASERCELL_VERSION;
  entry.provenance.date = NowUtc();
  entry.provenance.input_digest = digest.Text();
  entry.provenance.residual_summary = result.method + ": rms " + Fmt(result.rms_mm, 3) + " mm over " +
                                      std::to_string(result.points) + " points, 1-sigma " +
                                      Fmt(result.normal_sigma_deg, 3) + " deg / " + Fmt(result.offset_sigma_mm, 3) + " mm";
  graph.SetLaserPlane("laser", entry);
  SaveFrameGraph(args.cell, graph);
  if (!args.quiet) std::printf("%s -> %s\n", result.Summary().c_str(), args.cell.c_str());
}

}  // namespace

void AddCalibrateLaserCommand(CLI::App& calibrate) {
  CLI::App* cmd = calibrate.add_subcommand(
      "laser", "Laser plane in the sensor frame from white-plane sweeps at known heights, or from "
               "a laser stripe on a chessboard of unknown pose; updates the cell's `laser` plane");
  auto args = std::make_shared<LaserArgs>();
  cmd->add_option("--camera", args->camera, "Camera model (.cameramodel)")->required();
  cmd->add_option("--planes", args->planes, "Folder of white-plane sweeps plane_<i>.lcp (or a folder holding profiles/)");
  cmd->add_option("--heights-mm", args->heights, "Plate heights along the plate normal, one per plane_<i>.lcp, mm");
  cmd->add_option("--plate-normal", args->plate_normal,
                  "Unit normal of the white plate in the sensor frame, pointing towards the sensor (default 0,0,-1)");
  cmd->add_option("--plate-distance-mm", args->plate_distance_mm,
                  "Distance from the sensor origin to the height-0 plate along the plate normal (default: "
                  "estimated, needs >= 3 heights)");
  cmd->add_flag("--fixed-plate-normal", args->fixed_plate_normal,
               "Keep --plate-normal exactly (default: estimate its tilt towards the laser line)");
  cmd->add_option("--stripe-images", args->stripe_glob, "Images of a laser stripe on a chessboard (quoted glob)");
  cmd->add_option("--board", args->board, "chessboard:COLSxROWS:SQUARE_MM (inner corners, mm)");
  cmd->add_option("--laser-color", args->laser_color, "Laser colour in the stripe images: green, red or gray");
  cmd->add_option("--cell", args->cell, "Cell file to update (created when missing)")->required();
  cmd->add_option("--report", args->report, "HTML report to write");
  cmd->add_option("--json", args->json, "JSON summary to write");
  cmd->add_flag("--quiet", args->quiet, "No summary line");
  cmd->callback([args] { Run(*args); });
}

}  // namespace lasercell::tools
