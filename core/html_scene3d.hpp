#pragma once
// Interactive 3D views in the self-contained HTML reports (core/html_report.hpp): a sweep as a
// point cloud, posed meshes (CAD parts), coordinate frames (axis triads: x red, y green, z blue)
// and boxes (regions of interest, as wireframes), drawn by three.js and its OrbitControls
// (Debian's libjs-three, r111) whose text is inlined into the page when the report is written:
// the page fetches nothing.
//
// Conventions: positions in the scene's `units` (mm everywhere in lasercell), all objects in one
// world frame; poses are `world_from_<object>` (p_in_world = world_from_mesh * p_in_mesh). Bulk
// data goes into the page as base64 of little-endian float32 (positions) and uint32 (triangle
// indices) arrays; the few pose numbers as JSON. Colours are RGB in [0, 1], lit by an ambient and a
// head light in the view.
//
// Markup for headless tests: each view is a <div class="lc-view3d" data-view3d="1">; after its
// first frame is drawn the script sets data-view3d-drawn="1" and data-view3d-objects="N" (the
// number of objects drawn). Without WebGL the view shows a one-line notice instead and sets
// data-view3d-webgl="0"; the rest of the page is unaffected. Script errors are recorded in
// <body data-report-errors> like every other script error of the report.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace lasercell::report {

/// A point cloud, e.g. a sweep. Drawn as square points of roughly `size_mm` in the scene.
struct Scene3dPoints {
  std::string name;                            ///< Legend entry.
  std::vector<Eigen::Vector3f> positions;      ///< p_in_world, in the scene's units.
  std::array<float, 3> rgb{0.6f, 0.6f, 0.6f};  ///< Colour, RGB in [0, 1].
  float size_mm = 1.0f;                        ///< Point size in scene units (> 0).
  /// At most this many points go into the page (> 0): more are decimated with a uniform stride
  /// (see DecimatePoints), which keeps a 200000-point cloud at about 3 MB of page.
  std::size_t max_points = 200000;
};

/// A triangle mesh (e.g. a CAD part) at a pose.
struct Scene3dMesh {
  std::string name;                       ///< Legend entry.
  std::vector<Eigen::Vector3f> vertices;  ///< p_in_mesh, in the scene's units.
  std::vector<Eigen::Vector3i> faces;     ///< Vertex indices per triangle, each in [0, size).
  Eigen::Isometry3d world_from_mesh = Eigen::Isometry3d::Identity();  ///< Pose of the mesh.
  std::array<float, 3> rgb{0.8f, 0.5f, 0.2f};                         ///< Colour, RGB in [0, 1].
  float opacity = 1.0f;  ///< In (0, 1]; below 1 the mesh is transparent.
};

/// A coordinate frame drawn as three arrows (x red, y green, z blue) with its name as label.
struct Scene3dFrame {
  std::string name;  ///< Legend entry and label at the origin.
  Eigen::Isometry3d world_from_frame = Eigen::Isometry3d::Identity();  ///< Pose of the frame.
  float axis_length_mm = 30.0f;  ///< Arrow length in scene units (> 0).
};

/// An axis-aligned box in its own frame, drawn as a wireframe (e.g. a region of interest).
struct Scene3dBox {
  std::string name;                                                  ///< Legend entry.
  Eigen::Isometry3d world_from_box = Eigen::Isometry3d::Identity();  ///< Pose of the box frame.
  Eigen::Vector3d min_mm = Eigen::Vector3d::Zero();  ///< Lower corner in the box frame.
  Eigen::Vector3d max_mm = Eigen::Vector3d::Zero();  ///< Upper corner, >= min_mm per axis.
  std::array<float, 3> rgb{0.1f, 0.6f, 0.9f};        ///< Colour, RGB in [0, 1].
};

/// Everything one 3D view shows. The camera starts framed on the bounding box of all objects.
struct Scene3d {
  std::string title;  ///< Heading above the view.
  std::vector<Scene3dPoints> points;
  std::vector<Scene3dMesh> meshes;
  std::vector<Scene3dFrame> frames;
  std::vector<Scene3dBox> boxes;
  std::string units = "mm";  ///< Unit of all lengths, shown in the view's caption.

  /// Throws InputError naming the object and field when a value is out of range (non-finite
  /// coordinates, face indices out of range, size/opacity/length not positive, min > max).
  void Check() const;
};

/// The positions a view keeps of `positions`: all when there are at most `max_points`, else
/// exactly `max_points` of them at indices floor(i * n / max_points), i = 0..max_points-1 (a
/// uniform stride, the same result on every run). max_points must be > 0.
std::vector<Eigen::Vector3f> DecimatePoints(const std::vector<Eigen::Vector3f>& positions,
                                            std::size_t max_points);

/// Standard base64 (RFC 4648, with '=' padding) of `bytes`.
std::string Base64(const std::string& bytes);

/// The bytes of `values` as little-endian float32 (the layout the page decodes).
std::string Float32Bytes(const std::vector<float>& values);

/// The bytes of `values` as little-endian uint32 (triangle indices).
std::string Uint32Bytes(const std::vector<std::uint32_t>& values);

/// Where the three.js file is read from: `path` when not empty, else the environment variable
/// LASERCELL_THREE_JS when set and not empty, else Debian's
/// /usr/share/javascript/three/three.min.js (package libjs-three).
std::string ThreeJsPath(const std::string& path = "");

/// Where the camera controls are read from: examples/js/controls/OrbitControls.js in the folder
/// of `three_js_path`, as libjs-three installs them.
std::string OrbitControlsPath(const std::string& three_js_path);

/// The HTML of one view (heading, container, data), without the scripts; `index` makes the
/// element ids of several views in one page unique. Checks the scene (Scene3d::Check).
std::string Scene3dHtml(const Scene3d& scene, int index);

/// The scripts that draw every view of a page: three.js read from `three_js_path` and its
/// OrbitControls (OrbitControlsPath), both inlined, and the view code. Throws FileError naming
/// the path (and saying to install libjs-three) when a file cannot be read or is not three.js.
std::string Scene3dScripts(const std::string& three_js_path);

/// The CSS of the views (for the page's head).
std::string Scene3dStyle();

}  // namespace lasercell::report
