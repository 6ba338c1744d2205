// Laser profiles to points: lasercell.read_profiles (the .lcp profile file,
// triangulation/profile_io.hpp) as arrays, and lasercell.scan_profiles, the sweep assembly of
// `lasercell scan triangulate` (triangulation/sweep.hpp): profiles + camera + laser plane (given,
// or the cell's) + motion -> a PointCloud in the sensor, a linear sweep's or the cell's frame.
#include <pybind11/stl.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "calib/camera_model.hpp"
#include "core/frame_graph.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/linear_sweep.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/sweep.hpp"
#include "triangulation/triangulator.hpp"

namespace lasercell::python {
namespace {

using triangulation::ProfileSet;
using triangulation::SweepResult;
using ProfilesPtr = std::shared_ptr<ProfileSet>;

// One field of every profile: a (P,) array when `columns` is 0 and `per_column` false, else a
// (P, columns) array (columns may be 0: a profile file without joints gives (P, 0) joints).
template <typename T, typename Get>
py::array_t<T> Stack(const ProfileSet& set, std::size_t columns, bool per_column, Get get) {
  const std::size_t n = set.profiles.size();
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(n)};
  if (per_column) shape.push_back(static_cast<py::ssize_t>(columns));
  py::array_t<T> out(shape);
  T* data = out.mutable_data();
  const std::size_t stride = per_column ? columns : 1;
  for (std::size_t i = 0; i < n; ++i) get(set.profiles[i], data + i * stride);
  return out;
}

template <typename T>
void CopyRow(const std::vector<T>& row, T* out) {
  std::copy(row.begin(), row.end(), out);
}

triangulation::SweepMotion Motion(const std::string& name) {
  if (name == "none") return triangulation::SweepMotion::kNone;
  if (name == "linear") return triangulation::SweepMotion::kLinear;
  if (name == "robot") return triangulation::SweepMotion::kRobot;
  ThrowInput("motion: expected 'none', 'linear' or 'robot', got '" + name + "'");
}

// An (n,) integer array as int64, exactly (nanosecond clocks exceed a double's 53 bits); empty
// for None. TypeError for a non-integer dtype, InputError for another length.
std::vector<std::int64_t> Integers(const py::object& values, const std::string& arg,
                                   std::size_t n) {
  if (values.is_none()) return {};
  const py::array a = py::array::ensure(values);
  if (!a || (a.dtype().kind() != 'i' && a.dtype().kind() != 'u')) {
    throw py::type_error(arg + ": expected an integer array (int64 ns / counts)");
  }
  if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
    ThrowInput(arg + ": expected " + std::to_string(n) + " values (one per profile)");
  }
  const auto cast = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  return std::vector<std::int64_t>(cast.data(), cast.data() + n);
}

// A profile set from arrays: row_px (P, C) NaN where no peak; the rest optional.
ProfilesPtr MakeProfiles(const py::handle& row_px, const py::object& intensity,
                         const py::object& width_px, const py::object& timestamp_ns,
                         const py::object& sequence, const py::object& joints_rad,
                         std::uint32_t image_width, std::uint32_t image_height,
                         std::uint32_t first_column, const std::string& robot,
                         const std::string& metadata) {
  const py::array rows = py::array::ensure(row_px);
  if (!rows || rows.ndim() != 2) ThrowInput("row_px: expected shape (profiles, columns)");
  const auto p = static_cast<std::size_t>(rows.shape(0));
  const auto c = static_cast<std::size_t>(rows.shape(1));
  const auto flat = [&](const py::handle& a, const std::string& arg, std::size_t per_row) {
    return ToDoubles(py::array::ensure(a).attr("reshape")(-1), arg, p * per_row, false);
  };
  auto set = std::make_shared<ProfileSet>();
  set->header.image_width = image_width;
  set->header.image_height = image_height;
  set->header.first_column = first_column;
  set->header.columns = static_cast<std::uint32_t>(c);
  set->header.robot = robot;
  set->header.metadata = metadata;
  std::size_t joints = 0;
  std::vector<double> joint_values;
  if (!joints_rad.is_none()) {
    const py::array j = py::array::ensure(joints_rad);
    if (!j || j.ndim() != 2) ThrowInput("joints_rad: expected shape (profiles, joints)");
    joints = static_cast<std::size_t>(j.shape(1));
    joint_values = flat(j, "joints_rad", joints);
  }
  set->header.joint_count = static_cast<std::uint32_t>(joints);
  set->header.Check("ProfileSet");
  const std::vector<double> r = flat(rows, "row_px", c);
  const std::vector<double> in =
      intensity.is_none() ? std::vector<double>(p * c, 1.0) : flat(intensity, "intensity", c);
  const std::vector<double> w =
      width_px.is_none() ? std::vector<double>(p * c, 2.0) : flat(width_px, "width_px", c);
  const std::vector<std::int64_t> t = Integers(timestamp_ns, "timestamp_ns", p);
  const std::vector<std::int64_t> q = Integers(sequence, "sequence", p);
  for (std::size_t i = 0; i < p; ++i) {
    triangulation::Profile profile = triangulation::Profile::Empty(
        static_cast<std::uint32_t>(c), static_cast<std::uint32_t>(joints));
    profile.sequence = q.empty() ? i : static_cast<std::uint64_t>(q[i]);
    profile.timestamp_ns = t.empty() ? 0 : t[i];
    for (std::size_t k = 0; k < joints; ++k) profile.joints_rad[k] = joint_values[i * joints + k];
    for (std::size_t j = 0; j < c; ++j) {
      const double row = r[i * c + j];
      profile.row_px[j] = static_cast<float>(row);
      const bool peak = !std::isnan(row);
      profile.intensity[j] = peak ? static_cast<float>(in[i * c + j]) : 0.0f;
      profile.width_px[j] = peak ? static_cast<float>(w[i * c + j]) : 0.0f;
    }
    triangulation::CheckProfile(set->header, profile, "profile " + std::to_string(i));
    set->profiles.push_back(std::move(profile));
  }
  return set;
}

void BindProfiles(py::module_& m) {
  py::class_<ProfileSet, ProfilesPtr>(m, "ProfileSet", LC_DOC(triangulation_ProfileSet))
      .def(py::init(&MakeProfiles), py::arg("row_px"), py::arg("intensity") = py::none(),
           py::arg("width_px") = py::none(), py::arg("timestamp_ns") = py::none(),
           py::arg("sequence") = py::none(), py::arg("joints_rad") = py::none(),
           py::arg("image_width") = 1024, py::arg("image_height") = 1024,
           py::arg("first_column") = 0, py::arg("robot") = "", py::arg("metadata") = "",
           R"doc(Profiles from arrays (copied): row_px (P, C) subpixel peak rows, NaN where a
column has no peak; intensity (0..1, default 1) and width_px (FWHM, default 2) per peak;
timestamp_ns and sequence (P,) (default 0 and 0..P-1); joints_rad (P, J). The columns are image
columns first_column .. first_column + C - 1. InputError naming the field when they disagree
with the header.)doc")
      .def("__len__", [](const ProfileSet& s) { return s.profiles.size(); })
      .def_property_readonly(
          "image_width", [](const ProfileSet& s) { return s.header.image_width; },
          LC_DOC(triangulation_ProfileHeader_image_width))
      .def_property_readonly(
          "image_height", [](const ProfileSet& s) { return s.header.image_height; },
          LC_DOC(triangulation_ProfileHeader_image_height))
      .def_property_readonly(
          "first_column", [](const ProfileSet& s) { return s.header.first_column; },
          LC_DOC(triangulation_ProfileHeader_first_column))
      .def_property_readonly(
          "columns", [](const ProfileSet& s) { return s.header.columns; },
          LC_DOC(triangulation_ProfileHeader_columns))
      .def_property_readonly(
          "robot", [](const ProfileSet& s) { return s.header.robot; },
          LC_DOC(triangulation_ProfileHeader_robot))
      .def_property_readonly(
          "metadata", [](const ProfileSet& s) { return s.header.metadata; },
          LC_DOC(triangulation_ProfileHeader_metadata))
      .def_property_readonly(
          "sequence",
          [](const ProfileSet& s) {
            return Stack<std::uint64_t>(s, 0, false,
                                        [](const auto& p, auto* out) { *out = p.sequence; });
          },
          "(P,): " LC_DOC(triangulation_Profile_sequence))
      .def_property_readonly(
          "timestamp_ns",
          [](const ProfileSet& s) {
            return Stack<std::int64_t>(s, 0, false,
                                       [](const auto& p, auto* out) { *out = p.timestamp_ns; });
          },
          "(P,): " LC_DOC(triangulation_Profile_timestamp_ns))
      .def_property_readonly(
          "joints_rad",
          [](const ProfileSet& s) {
            return Stack<double>(s, s.header.joint_count, true,
                                 [](const auto& p, auto* out) { CopyRow(p.joints_rad, out); });
          },
          "(P, J), one row per profile: " LC_DOC(triangulation_Profile_joints_rad))
      .def_property_readonly(
          "row_px",
          [](const ProfileSet& s) {
            return Stack<float>(s, s.header.columns, true,
                                [](const auto& p, auto* out) { CopyRow(p.row_px, out); });
          },
          "(P, C), one row per profile: " LC_DOC(triangulation_Profile_row_px))
      .def_property_readonly(
          "intensity",
          [](const ProfileSet& s) {
            return Stack<float>(s, s.header.columns, true,
                                [](const auto& p, auto* out) { CopyRow(p.intensity, out); });
          },
          "(P, C), one row per profile: " LC_DOC(triangulation_Profile_intensity))
      .def_property_readonly(
          "width_px",
          [](const ProfileSet& s) {
            return Stack<float>(s, s.header.columns, true,
                                [](const auto& p, auto* out) { CopyRow(p.width_px, out); });
          },
          "(P, C), one row per profile: " LC_DOC(triangulation_Profile_width_px))
      .def("__repr__", [](const ProfileSet& s) {
        return "<lasercell.ProfileSet " + std::to_string(s.profiles.size()) + " profiles x " +
               std::to_string(s.header.columns) + " columns>";
      });

  m.def(
      "write_profiles",
      [](const std::string& path, const ProfileSet& profiles) {
        py::gil_scoped_release release;
        triangulation::WriteProfiles(path, profiles);
      },
      py::arg("path"), py::arg("profiles"), "Writes a .lcp profile file atomically.");
  m.def(
      "read_profiles",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<ProfileSet>(triangulation::ReadProfiles(path));
      },
      py::arg("path"), "Reads a .lcp profile file; FileError naming the problem.");
}

void BindSweep(py::module_& m) {
  py::class_<SweepResult, std::shared_ptr<SweepResult>>(m, "Sweep",
                                                        "Profiles turned into one cloud.")
      .def_property_readonly(
          "cloud",
          [](const std::shared_ptr<SweepResult>& s) {
            // The cloud shares the sweep's lifetime (aliasing pointer, no copy).
            return std::shared_ptr<PointCloud>(s, &s->cloud);
          },
          "The points (organized: grid = (profiles, columns)), mm, in `frame`.")
      .def_readonly("frame", &SweepResult::frame, LC_DOC(triangulation_SweepResult_frame))
      .def_readonly("profiles", &SweepResult::profiles, LC_DOC(triangulation_SweepResult_profiles))
      .def_readonly("sequence_gaps", &SweepResult::sequence_gaps,
                    LC_DOC(triangulation_SweepResult_sequence_gaps))
      .def_property_readonly(
          "counts",
          [](const SweepResult& s) {
            py::dict d;
            d["points"] = s.counts.points;
            d["no_peak"] = s.counts.no_peak;
            d["outside_image"] = s.counts.outside_image;
            d["parallel"] = s.counts.parallel;
            d["behind_camera"] = s.counts.behind_camera;
            d["out_of_range"] = s.counts.out_of_range;
            return d;
          },
          "Valid points and rejections by reason, over all profiles.")
      .def_property_readonly(
          "frame_from_sensor",
          [](const SweepResult& s) {
            py::array_t<double> out({static_cast<py::ssize_t>(s.frame_from_sensor.size()),
                                     py::ssize_t{4}, py::ssize_t{4}});
            auto view = out.mutable_unchecked<3>();
            for (std::size_t i = 0; i < s.frame_from_sensor.size(); ++i) {
              const Eigen::Matrix4d& t = s.frame_from_sensor[i].matrix();
              for (int r = 0; r < 4; ++r) {
                for (int c = 0; c < 4; ++c) view(static_cast<py::ssize_t>(i), r, c) = t(r, c);
              }
            }
            return out;
          },
          "(P, 4, 4): the sensor pose of each profile in the sweep frame.")
      .def("summary", &SweepResult::Summary, LC_DOC(triangulation_SweepResult_Summary))
      .def("__repr__",
           [](const SweepResult& s) { return "<lasercell.Sweep " + s.Summary() + ">"; });
}

}  // namespace

void BindTriangulation(py::module_& m) {
  BindProfiles(m);
  BindSweep(m);
  m.def(
      "scan_profiles",
      [](const ProfileSet& profiles, const calib::CameraModel& camera, const py::object& plane,
         const FrameGraph* cell, const std::string& laser, const std::string& motion,
         const py::object& velocity_mm_s, std::optional<std::int64_t> t0_ns,
         const std::string& linear_record, const std::string& target_frame,
         const std::string& robot, bool exact, int threads) {
        triangulation::SweepOptions options;
        if (!linear_record.empty()) {
          if (motion != "none" && motion != "linear") {
            ThrowInput("linear_record: a linear sweep record sets motion 'linear'; drop motion='" +
                       motion + "'");
          }
          options = triangulation::ReadLinearSweepRecord(linear_record).Options();
        } else {
          options.motion = Motion(motion);
          if (!velocity_mm_s.is_none()) {
            options.velocity_mm_s = ToVector3(velocity_mm_s, "velocity_mm_s");
          }
          if (t0_ns) options.t0_ns = *t0_ns;
        }
        options.target_frame = target_frame;
        options.robot = robot;
        options.path = exact ? triangulation::TriangulationPath::kExact
                             : triangulation::TriangulationPath::kFast;
        options.threads = threads;
        triangulation::LaserPlaneSource source;
        source.laser = laser;
        if (!plane.is_none()) {
          source.plane = ToVector4(plane, "laser_plane");
          source.plane_label = "laser_plane";
        }
        py::gil_scoped_release release;
        const triangulation::ScanSetup setup =
            triangulation::ScanSetupFromCell(cell, "cell", source, options);
        const triangulation::Triangulator triangulator(camera, setup.laser_plane);
        return std::make_shared<SweepResult>(
            triangulation::AssembleSweep(profiles, triangulator, setup.options, cell));
      },
      py::arg("profiles"), py::arg("camera"), py::arg("laser_plane") = py::none(),
      py::arg("cell") = nullptr, py::arg("laser") = "laser", py::arg("motion") = "none",
      py::arg("velocity_mm_s") = py::none(), py::arg("t0_ns") = py::none(),
      py::arg("linear_record") = "", py::arg("target_frame") = "", py::arg("robot") = "",
      py::arg("exact") = false, py::arg("threads") = 1,
      R"doc(Profiles -> a calibrated sweep, as `lasercell scan triangulate` does.

laser_plane: (4,) (n, d) with n . p + d = 0 in the sensor frame, mm; None takes the plane named
`laser` from `cell` (a FrameGraph). motion: 'none' (static sensor), 'linear' (velocity_mm_s in
the sensor frame at t0_ns; or linear_record, a records/linear_sweep.yaml, which sets both) or
'robot' (joints in the profiles, through the cell to target_frame). exact: mrcal per pixel
instead of the lookup tables. Raises InputError when the profiles do not fit the camera or the
cell has no path to target_frame.)doc");
}

}  // namespace lasercell::python
