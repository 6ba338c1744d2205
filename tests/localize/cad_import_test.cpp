#include "localize/cad_import.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <initializer_list>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "core/error.hpp"
#include "localize/cad_export.hpp"
#include "tests/cli_util.hpp"
#include "tests/sanitizer_scale.hpp"

namespace lasercell::localize {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The test parts, in their own "plate" frame: a 40 x 30 x 5 mm plate from the origin corner,
// either with a through-hole of radius 6 around (20, 15) or with a cylinder of radius 6 and
// height 7 standing on its top face at (20, 15). The whole part is placed in the part frame by
// part_from_plate, so the primitives' placements are exercised too.
constexpr double kX = 40, kY = 30, kZ = 5, kR = 6, kBossHeight = 7;
const Eigen::Vector2d kAxis(20, 15);

Eigen::Isometry3d PartFromPlate() {
  Eigen::Isometry3d part_from_plate = Eigen::Isometry3d::Identity();
  part_from_plate.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  part_from_plate.translation() = Eigen::Vector3d(12.5, -7.25, 3.0);
  return part_from_plate;
}

CadSolid PlateWithHole(const Eigen::Isometry3d& part_from_plate) {
  CadPrimitive box;
  box.kind = CadPrimitive::kBox;
  box.part_from_primitive = part_from_plate;
  box.size_mm = Eigen::Vector3d(kX, kY, kZ);
  CadPrimitive hole;
  hole.kind = CadPrimitive::kCylinder;
  hole.part_from_primitive = part_from_plate * Eigen::Translation3d(kAxis.x(), kAxis.y(), -1);
  hole.size_mm = Eigen::Vector3d(kR, kZ + 2, 0);
  hole.subtract = true;
  return CadSolid{{box, hole}};
}

CadSolid PlateWithBoss(const Eigen::Isometry3d& part_from_plate) {
  CadSolid solid = PlateWithHole(part_from_plate);
  solid.primitives[1].part_from_primitive =
      part_from_plate * Eigen::Translation3d(kAxis.x(), kAxis.y(), kZ);
  solid.primitives[1].size_mm = Eigen::Vector3d(kR, kBossHeight, 0);
  solid.primitives[1].subtract = false;
  return solid;
}

// One analytic face of a test part, in the plate frame: distance of a point to its (unbounded)
// surface, the outward normal at the point's foot, and whether the point lies on the bounded
// face (within `tol`).
struct AnalyticFace {
  std::string name;
  std::function<double(const Eigen::Vector3d&)> distance;
  std::function<Eigen::Vector3d(const Eigen::Vector3d&)> normal;
  std::function<bool(const Eigen::Vector3d&, double)> contains;
};

double Radial(const Eigen::Vector3d& q) { return (q.head<2>() - kAxis).norm(); }

AnalyticFace Plane(const std::string& name, int axis, double at, double sign,
                   std::function<bool(const Eigen::Vector3d&, double)> contains) {
  return {
      name, [=](const Eigen::Vector3d& q) { return std::abs(q[axis] - at); },
      [=](const Eigen::Vector3d&) { return Eigen::Vector3d(sign * Eigen::Vector3d::Unit(axis)); },
      std::move(contains)};
}

AnalyticFace CylinderWall(const std::string& name, double z0, double z1, double sign) {
  return {
      name, [](const Eigen::Vector3d& q) { return std::abs(Radial(q) - kR); },
      [=](const Eigen::Vector3d& q) {
        Eigen::Vector3d n(q.x() - kAxis.x(), q.y() - kAxis.y(), 0);
        return Eigen::Vector3d(sign * n.normalized());
      },
      [=](const Eigen::Vector3d& q, double tol) { return q.z() >= z0 - tol && q.z() <= z1 + tol; }};
}

// The faces of the plate (hole: sign -1 wall, the top and bottom faces exclude the disk) or the
// plate with the boss (top face excludes the disk, plus the wall and the boss top).
std::vector<AnalyticFace> AnalyticFaces(bool boss) {
  const auto in_xy = [](const Eigen::Vector3d& q, double tol) {
    return q.x() >= -tol && q.x() <= kX + tol && q.y() >= -tol && q.y() <= kY + tol;
  };
  const auto in_xz = [](const Eigen::Vector3d& q, double tol) {
    return q.x() >= -tol && q.x() <= kX + tol && q.z() >= -tol && q.z() <= kZ + tol;
  };
  const auto in_yz = [](const Eigen::Vector3d& q, double tol) {
    return q.y() >= -tol && q.y() <= kY + tol && q.z() >= -tol && q.z() <= kZ + tol;
  };
  using Contains = std::function<bool(const Eigen::Vector3d&, double)>;
  const Contains outside_disk = [=](const Eigen::Vector3d& q, double tol) {
    return in_xy(q, tol) && Radial(q) >= kR - tol;
  };
  std::vector<AnalyticFace> faces = {
      Plane("x=0", 0, 0, -1, in_yz),
      Plane("x=max", 0, kX, 1, in_yz),
      Plane("y=0", 1, 0, -1, in_xz),
      Plane("y=max", 1, kY, 1, in_xz),
      Plane("z=0", 2, 0, -1, boss ? Contains(in_xy) : outside_disk),
      Plane("z=max", 2, kZ, 1, outside_disk),
  };
  if (boss) {
    faces.push_back(CylinderWall("boss wall", kZ, kZ + kBossHeight, 1));
    faces.push_back(
        Plane("boss top", 2, kZ + kBossHeight, 1,
              [](const Eigen::Vector3d& q, double tol) { return Radial(q) <= kR + tol; }));
  } else {
    faces.push_back(CylinderWall("hole wall", 0, kZ, -1));
  }
  return faces;
}

double AnalyticArea(bool boss) {
  const double sides = 2 * (kX + kY) * kZ;
  if (boss) return 2 * kX * kY + sides + 2 * kPi * kR * kBossHeight;
  return 2 * (kX * kY - kPi * kR * kR) + sides + 2 * kPi * kR * kZ;
}

double AnalyticVolume(bool boss) {
  const double disk = kPi * kR * kR;
  return kX * kY * kZ + (boss ? disk * kBossHeight : -disk * kZ);
}

// Worst deviations of oriented points from the analytic faces (each point judged against the
// face whose surface it is nearest to, among the faces that contain it).
struct Deviation {
  double max_distance_mm = 0;
  double max_angle_deg = 0;
  std::size_t unassigned = 0;       // points on no face
  std::map<std::string, int> hits;  // points per face
  double min_outward_dot = 1;       // convex faces: n . (p - centroid) / |p - centroid|
  double min_hole_dot = 1;          // hole wall: n . (axis foot - p) / |.|
};

Deviation MeasureDeviation(const PointCloud& points, bool boss,
                           const Eigen::Isometry3d& part_from_plate) {
  const std::vector<AnalyticFace> faces = AnalyticFaces(boss);
  const Eigen::Isometry3d plate_from_part = part_from_plate.inverse();
  const Eigen::Vector3d centroid(kX / 2, kY / 2, kZ / 2);
  Deviation d;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d q = plate_from_part * points.positions[i];
    const Eigen::Vector3d n = plate_from_part.linear() * points.normals[i];
    const AnalyticFace* best = nullptr;
    double best_distance = 1e9;
    for (const AnalyticFace& face : faces) {
      const double distance = face.distance(q);
      if (face.contains(q, 0.02) && distance < best_distance) {
        best = &face;
        best_distance = distance;
      }
    }
    if (best == nullptr) {
      ++d.unassigned;
      continue;
    }
    ++d.hits[best->name];
    d.max_distance_mm = std::max(d.max_distance_mm, best_distance);
    const double cos_angle = std::clamp(n.dot(best->normal(q)), -1.0, 1.0);
    d.max_angle_deg = std::max(d.max_angle_deg, std::acos(cos_angle) * 180 / kPi);
    if (best->name == "hole wall") {
      const Eigen::Vector3d foot(kAxis.x(), kAxis.y(), q.z());
      d.min_hole_dot = std::min(d.min_hole_dot, n.dot((foot - q).normalized()));
    } else {  // the other faces bound convex pieces around the centroid's vertical
      d.min_outward_dot = std::min(d.min_outward_dot, n.dot((q - centroid).normalized()));
    }
  }
  return d;
}

// Closedness and orientation of a mesh whose faces have their own vertices: positions that
// agree to 1e-4 mm are one vertex; a closed, consistently oriented surface uses every directed
// edge exactly once and its reverse exactly once.
struct MeshCheck {
  std::size_t unmatched_edges = 0;
  double volume_mm3 = 0;           // divergence theorem, positive when faces point outward
  double area_mm2 = 0;             // sum of the triangle areas
  double min_normal_dot = 1;       // vertex normal . triangle normal, over all corners
  double max_vertex_distance = 0;  // vertex to the nearest analytic face
};

MeshCheck CheckMesh(const TriangleMesh& mesh, bool boss, const Eigen::Isometry3d& part_from_plate) {
  MeshCheck c;
  const auto& v = mesh.vertices.positions;
  std::map<std::tuple<long, long, long>, int> ids;
  std::vector<int> id(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const auto key = std::make_tuple(std::lround(v[i].x() * 1e4), std::lround(v[i].y() * 1e4),
                                     std::lround(v[i].z() * 1e4));
    id[i] = ids.emplace(key, static_cast<int>(ids.size())).first->second;
  }
  std::map<std::pair<int, int>, int> directed;
  for (const Eigen::Vector3i& f : mesh.faces) {
    const Eigen::Vector3d cross = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]);
    c.area_mm2 += 0.5 * cross.norm();
    c.volume_mm3 += v[f[0]].dot(v[f[1]].cross(v[f[2]])) / 6;
    for (int k = 0; k < 3; ++k) {
      c.min_normal_dot =
          std::min(c.min_normal_dot, mesh.vertices.normals[f[k]].dot(cross.normalized()));
      const int a = id[f[k]], b = id[f[(k + 1) % 3]];
      if (a != b) ++directed[{a, b}];
    }
  }
  for (const auto& [edge, count] : directed) {
    const auto reverse = directed.find({edge.second, edge.first});
    if (count != 1 || reverse == directed.end() || reverse->second != 1) ++c.unmatched_edges;
  }
  const Deviation d = MeasureDeviation(mesh.vertices, boss, part_from_plate);
  c.max_vertex_distance = d.unassigned > 0 ? 1e9 : d.max_distance_mm;
  return c;
}

// Checks one model read back from a file against the analytic part.
void ExpectMatchesAnalyticPart(const CadModel& model, bool boss,
                               const Eigen::Isometry3d& part_from_plate, double step_mm) {
  EXPECT_EQ(model.solids, 1u);
  EXPECT_EQ(model.shells, 1u);
  EXPECT_EQ(model.faces, boss ? 8u : 7u);
  const double area = AnalyticArea(boss);
  EXPECT_NEAR(model.surface_area_mm2, area, 1e-3 * area);

  ASSERT_EQ(model.samples.normals.size(), model.samples.size());
  const Deviation d = MeasureDeviation(model.samples, boss, part_from_plate);
  EXPECT_EQ(d.unassigned, 0u);
  EXPECT_LE(d.max_distance_mm, 0.01);
  EXPECT_LE(d.max_angle_deg, 0.1);
  EXPECT_GT(d.min_outward_dot, 0.0);
  if (!boss) {
    EXPECT_GT(d.min_hole_dot, 0.999);  // hole-wall normals point at the axis
  }
  EXPECT_EQ(d.hits.size(), boss ? 8u : 7u) << "every face is sampled";
  const auto text = [](double x) {
    std::ostringstream out;
    out << x;
    return out.str();
  };
  ::testing::Test::RecordProperty("max_distance_mm", text(d.max_distance_mm));
  ::testing::Test::RecordProperty("max_angle_deg", text(d.max_angle_deg));
  // About one point per step^2 of surface: the grid steps are at most step_mm and round the
  // face sizes up to whole cells, so the count is at least area / step^2 and not much more.
  const double expected = area / (step_mm * step_mm);
  EXPECT_GE(static_cast<double>(model.samples.size()), 0.97 * expected);
  EXPECT_LE(static_cast<double>(model.samples.size()), 1.25 * expected);

  const MeshCheck m = CheckMesh(model.mesh, boss, part_from_plate);
  EXPECT_EQ(m.unmatched_edges, 0u) << "closed, consistently oriented mesh";
  EXPECT_GT(m.min_normal_dot, 0.5) << "vertex normals agree with the counter-clockwise faces";
  EXPECT_LE(m.max_vertex_distance, 1e-5);
  // Chords cut the cylinder: the volume and area differ from the exact ones by at most the
  // chord error times the wall's area (and a bit less).
  const double wall = 2 * kPi * kR * (boss ? kBossHeight : kZ);
  EXPECT_NEAR(m.volume_mm3, AnalyticVolume(boss), 0.05 * wall + 1e-6);
  EXPECT_NEAR(m.area_mm2, area, 0.05 * 2 * kPi * kR * 2 + 0.01 * wall);
}

TEST(CadImport, PlateWithHoleRoundTripsThroughStepAndIges) {
  const test::TestDir dir("cad_import");
  const Eigen::Isometry3d part_from_plate = PartFromPlate();
  for (const std::string name : {"plate.step", "plate.igs"}) {
    SCOPED_TRACE(name);
    const std::string path = dir.File(name);
    WriteCadSolid(path, PlateWithHole(part_from_plate));
    const CadModel model = ReadCadModel(path);
    EXPECT_EQ(model.format, name.ends_with(".step") ? "step" : "iges");
    EXPECT_EQ(model.source_unit, "mm");
    EXPECT_EQ(model.scale_to_mm, 1.0);
    ExpectMatchesAnalyticPart(model, false, part_from_plate, 1.0);
  }
}

TEST(CadImport, UnionOfBoxAndCylinderRoundTripsThroughStepAndIges) {
  const test::TestDir dir("cad_import");
  const Eigen::Isometry3d part_from_plate = PartFromPlate();
  CadImportOptions options;
  options.sampling_step_mm = 0.7;
  for (const std::string name : {"boss.stp", "boss.iges"}) {
    SCOPED_TRACE(name);
    const std::string path = dir.File(name);
    WriteCadSolid(path, PlateWithBoss(part_from_plate));
    ExpectMatchesAnalyticPart(ReadCadModel(path, options), true, part_from_plate, 0.7);
  }
}

// The largest |coordinate| of the 3D CARTESIAN_POINTs in STEP text (not the 2D points of the
// curves in surface parameters), in the file's own unit.
double MaxStepCoordinate(const std::string& text) {
  const std::regex point(R"(CARTESIAN_POINT\('[^']*',\(([^,)]*,[^,)]*,[^,)]*)\)\))");
  double max = 0;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), point);
       it != std::sregex_iterator(); ++it) {
    std::string coords = (*it)[1];
    std::replace(coords.begin(), coords.end(), ',', ' ');
    std::istringstream in(coords);
    for (double x = 0; in >> x;) max = std::max(max, std::abs(x));
  }
  return max;
}

TEST(CadImport, FilesInInchesAndMetresReadBackInMillimetres) {
  const test::TestDir dir("cad_import");
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const CadSolid plate = PlateWithHole(identity);
  const struct {
    std::string unit;
    double mm;
    std::string iges_unit_field;  // IGES global section parameters 14-15
  } units[] = {{"mm", 1.0, ",2,2HMM,"}, {"inch", 25.4, ",1,4HINCH,"}, {"m", 1000.0, ",6,1HM,"}};
  for (const auto& u : units) {
    for (const std::string ext : {".step", ".igs"}) {
      SCOPED_TRACE(u.unit + ext);
      const std::string path = dir.File("plate_" + u.unit + ext);
      WriteCadSolid(path, plate, u.unit);
      const std::string text = test::Slurp(path);
      if (ext == ".step") {
        // The file holds the coordinates in its unit: the 40 mm corner is 40 / mm-per-unit.
        EXPECT_NEAR(MaxStepCoordinate(text) * u.mm, kX, 1e-6);
      } else {
        EXPECT_NE(text.find(u.iges_unit_field), std::string::npos);
      }
      const CadModel model = ReadCadModel(path);
      EXPECT_EQ(model.source_unit, u.unit);
      EXPECT_DOUBLE_EQ(model.scale_to_mm, u.mm);
      const BoundingBox box = model.samples.Bounds();
      const BoundingBox mesh_box = model.mesh.vertices.Bounds();
      EXPECT_LT((mesh_box.min - Eigen::Vector3d::Zero()).norm(), 1e-6);
      EXPECT_LT((mesh_box.max - Eigen::Vector3d(kX, kY, kZ)).norm(), 1e-6);
      EXPECT_GT((box.min - mesh_box.min).minCoeff(), -1e-6);  // samples within the mesh's box
      EXPECT_GT((mesh_box.max - box.max).minCoeff(), -1e-6);
      EXPECT_NEAR(model.surface_area_mm2, AnalyticArea(false), 1e-3 * AnalyticArea(false));
      ExpectMatchesAnalyticPart(model, false, identity, 1.0);
    }
  }
}

TEST(CadImport, ExtensionIsCaseInsensitiveAndReadsAreDeterministicAndThreadSafe) {
  const test::TestDir dir("cad_import");
  const std::string path = dir.File("PLATE.STP");
  WriteCadSolid(path, PlateWithHole(Eigen::Isometry3d::Identity()));
  CadImportOptions options;
  options.sampling_step_mm = 2.0;
  const CadModel a = ReadCadModel(path, options);
  const CadModel b = ReadCadModel(path, options);
  EXPECT_EQ(a.format, "step");
  ASSERT_EQ(a.samples.size(), b.samples.size());
  EXPECT_EQ(a.samples.positions, b.samples.positions);
  EXPECT_EQ(a.samples.normals, b.samples.normals);
  EXPECT_EQ(a.mesh.faces, b.mesh.faces);
  // Concurrent reads and writes (OpenCASCADE's settings are process-wide) give the same model.
  // Under ASan the threads take turns: its allocator is not fork-safe (tests/sanitizer_scale.hpp),
  // and a read forks while the other thread allocates.
  std::vector<CadModel> models(2);
  std::vector<std::string> errors(2);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < models.size(); ++t) {
    threads.emplace_back([&, t] {
      try {
        WriteCadSolid(dir.File("thread" + std::to_string(t) + ".igs"),
                      PlateWithBoss(Eigen::Isometry3d::Identity()), t == 0 ? "inch" : "m");
        models[t] = ReadCadModel(path, options);
      } catch (const std::exception& e) {
        errors[t] = e.what();
      }
    });
    if (!test::kAllocatorForkSafe) threads.back().join();
  }
  for (std::thread& thread : threads) {
    if (thread.joinable()) thread.join();
  }
  EXPECT_EQ(errors, std::vector<std::string>(2));
  for (const CadModel& model : models) EXPECT_EQ(model.samples.positions, a.samples.positions);
  // Each concurrent write kept its own unit (the unit is a process-wide OpenCASCADE setting).
  const CadModel inch = ReadCadModel(dir.File("thread0.igs"), options);
  const CadModel metre = ReadCadModel(dir.File("thread1.igs"), options);
  EXPECT_EQ(inch.source_unit, "inch");
  EXPECT_EQ(metre.source_unit, "m");
  EXPECT_EQ(inch.faces, 8u);
  EXPECT_NEAR(metre.surface_area_mm2, AnalyticArea(true), 1e-3 * AnalyticArea(true));
  // A coarser step gives proportionally fewer points.
  const double expected = AnalyticArea(false) / 4;
  EXPECT_GE(static_cast<double>(a.samples.size()), 0.97 * expected);
  EXPECT_LE(static_cast<double>(a.samples.size()), 1.25 * expected);
}

// A STEP export of a single line segment (a wireframe, no surfaces), as OpenCASCADE 7.6 writes
// it, and the same segment as IGES (entity 110).
constexpr const char* kWireframeStep = R"(ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('Open CASCADE Model'),'2;1');
FILE_NAME('Open CASCADE Shape Model','2026-12-02T03:28:11',('Author'),(
    'Open CASCADE'),'Open CASCADE STEP processor 7.6','Open CASCADE 7.6'
  ,'Unknown');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));
ENDSEC;
DATA;
#1 = APPLICATION_PROTOCOL_DEFINITION('international standard',
  'automotive_design',2000,#2);
#2 = APPLICATION_CONTEXT(
  'core data for automotive mechanical design processes');
#3 = SHAPE_DEFINITION_REPRESENTATION(#4,#10);
#4 = PRODUCT_DEFINITION_SHAPE('','',#5);
#5 = PRODUCT_DEFINITION('design','',#6,#9);
#6 = PRODUCT_DEFINITION_FORMATION('','',#7);
#7 = PRODUCT('Open CASCADE STEP translator 7.6 1',
  'Open CASCADE STEP translator 7.6 1','',(#8));
#8 = PRODUCT_CONTEXT('',#2,'mechanical');
#9 = PRODUCT_DEFINITION_CONTEXT('part definition',#2,'design');
#10 = GEOMETRICALLY_BOUNDED_WIREFRAME_SHAPE_REPRESENTATION('',(#11,#15),
  #23);
#11 = AXIS2_PLACEMENT_3D('',#12,#13,#14);
#12 = CARTESIAN_POINT('',(0.,0.,0.));
#13 = DIRECTION('',(0.,0.,1.));
#14 = DIRECTION('',(1.,0.,-0.));
#15 = GEOMETRIC_CURVE_SET('',(#16));
#16 = TRIMMED_CURVE('',#17,(#21,PARAMETER_VALUE(0.)),(#22,
    PARAMETER_VALUE(1.)),.T.,.PARAMETER.);
#17 = LINE('',#18,#19);
#18 = CARTESIAN_POINT('',(0.,0.,0.));
#19 = VECTOR('',#20,1.);
#20 = DIRECTION('',(1.,0.,0.));
#21 = CARTESIAN_POINT('',(0.,0.,0.));
#22 = CARTESIAN_POINT('',(1.,0.,0.));
#23 = ( GEOMETRIC_REPRESENTATION_CONTEXT(3) 
GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#27)) GLOBAL_UNIT_ASSIGNED_CONTEXT(
(#24,#25,#26)) REPRESENTATION_CONTEXT('Context #1',
  '3D Context with UNIT and UNCERTAINTY') );
#24 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );
#25 = ( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) );
#26 = ( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() );
#27 = UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#24,
  'distance_accuracy_value','confusion accuracy');
#28 = PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#7));
ENDSEC;
END-ISO-10303-21;
)";
constexpr const char* kWireframeIges =
    "                                                                        S0000001\n"
    ",,31HOpen CASCADE IGES processor 7.6,13HFilename.iges,                  G0000001\n"
    "16HOpen CASCADE 7.6,31HOpen CASCADE IGES processor 7.6,32,308,15,308,15,G0000002\n"
    ",1.,2,2HMM,1,0.01,15H20261202.032811,1E-07,1.,4Hroot,,11,0,             G0000003\n"
    "15H20261202.032811,;                                                    G0000004\n"
    "     110       1       0       0       0       0       0       000000000D0000001\n"
    "     110       0       0       1       0                               0D0000002\n"
    "110,0.,0.,0.,1.,0.,0.;                                           0000001P0000001\n"
    "S      1G      4D      2P      1                                        T0000001\n";

// Runs `read` and checks it throws E with a message holding every one of `parts`.
template <typename E, typename F>
void ExpectError(F read, std::initializer_list<std::string> parts) {
  try {
    read();
    ADD_FAILURE() << "no exception";
  } catch (const E& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "'" << part << "' not in: " << e.what();
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

std::string Replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(CadImportErrors, MissingUnreadableAndMisnamedFilesNameTheFile) {
  const test::TestDir dir("cad_import");
  const std::string missing = dir.File("missing.step");
  ExpectError<FileError>([&] { ReadCadModel(missing); }, {missing, "does not exist"});
  const std::string folder = dir.File("folder.igs");
  std::filesystem::create_directories(folder);
  ExpectError<FileError>([&] { ReadCadModel(folder); }, {folder, "directory"});
  const std::string stl = dir.File("part.stl");
  test::Spit(stl, "solid x\nendsolid x\n");
  ExpectError<InputError>([&] { ReadCadModel(stl); }, {stl, "'.stl'", ".step", ".igs"});
  const std::string none = dir.File("part");
  ExpectError<InputError>([&] { ReadCadModel(none); }, {none, "extension"});
  const std::string empty = dir.File("empty.igs");
  test::Spit(empty, "");
  ExpectError<InputError>([&] { ReadCadModel(empty); }, {empty, "is empty"});
}

TEST(CadImportErrors, ContentThatIsNotStepOrIgesIsAnInputErrorWithTheReaderStatus) {
  const test::TestDir dir("cad_import");
  const std::string garbage = "this is not a CAD file\n";
  for (const std::string name : {"text.step", "text.stp", "text.iges", "text.igs"}) {
    const std::string path = dir.File(name);
    test::Spit(path, garbage);
    const bool step = name.find(".st") != std::string::npos;
    // STEP: OpenCASCADE's parser rejects it; IGES: its lenient reader would take the text for
    // an empty file, so the Start-section record is checked first.
    ExpectError<InputError>([&] { ReadCadModel(path); },
                            {path, step ? "not a readable STEP file" : "not a readable IGES file",
                             step ? "OpenCASCADE status Ret" : "column 73"});
  }
  // A STEP file cut off after its header.
  const test::TestDir dir2("cad_import_cut");
  const std::string whole = dir2.File("whole.step");
  WriteCadSolid(whole, PlateWithHole(Eigen::Isometry3d::Identity()));
  const std::string text = test::Slurp(whole);
  const std::string cut = dir2.File("cut.step");
  test::Spit(cut, text.substr(0, text.find("DATA;")));
  ExpectError<InputError>([&] { ReadCadModel(cut); }, {cut, "not a readable STEP file"});
}

// OpenCASCADE's IGES translator dereferences a null entity (SIGSEGV inside libTKIGES) on this
// file: one byte of a directory entry damaged (kept by the fuzz target `cad`; its first byte
// chose IGES). The read runs in a child process, so the crash is this file's error.
TEST(CadImportErrors, AFileThatCrashesOpenCascadeIsAnInputErrorNotACrash) {
  const test::TestDir dir("cad_import");
  const std::string kept =
      test::Slurp(std::string(LASERCELL_SOURCE_DIR) +
                  "/tests/fuzz/regressions/cad/iges-damaged-loop-directory-entry");
  const std::string iges = dir.File("damaged.igs");
  test::Spit(iges, kept.substr(1));
  ExpectError<InputError>([&] { ReadCadModel(iges); },
                          {iges, "OpenCASCADE crashed", "signal 11", "export the part again"});
  // The process is intact: the next read works.
  const std::string good = dir.File("good.igs");
  WriteCadSolid(good, PlateWithHole(Eigen::Isometry3d::Identity()));
  EXPECT_GT(ReadCadModel(good).samples.size(), 100u);
}

TEST(CadImportErrors, FilesWithoutSurfacesAskForASolid) {
  const test::TestDir dir("cad_import");
  const std::string step = dir.File("wire.step");
  test::Spit(step, kWireframeStep);
  ExpectError<InputError>([&] { ReadCadModel(step); },
                          {step, "holds no surfaces", "export the part as a solid"});
  const std::string iges = dir.File("wire.igs");
  test::Spit(iges, kWireframeIges);
  ExpectError<InputError>([&] { ReadCadModel(iges); },
                          {iges, "holds no surfaces", "export the part as a solid"});
}

TEST(CadImportErrors, UnknownLengthUnitsAreRejected) {
  const test::TestDir dir("cad_import");
  const CadSolid plate = PlateWithHole(Eigen::Isometry3d::Identity());
  const std::string inch = dir.File("inch.step");
  WriteCadSolid(inch, plate, "inch");
  const std::string furlong = dir.File("furlong.step");
  test::Spit(furlong, Replaced(test::Slurp(inch), "'INCH'", "'FURLONG'"));
  ExpectError<InputError>([&] { ReadCadModel(furlong); },
                          {furlong, "unknown or unsupported length unit 'FURLONG'"});
  // IGES: unit flag 3 ("named in the next parameter") with a name no reader knows.
  const std::string mm = dir.File("mm.igs");
  WriteCadSolid(mm, plate, "mm");
  const std::string named = dir.File("named.igs");
  test::Spit(named, Replaced(test::Slurp(mm), ",2,2HMM,", ",3,2HFU,"));
  ExpectError<InputError>([&] { ReadCadModel(named); },
                          {named, "unknown or unsupported length unit 'FU'"});
}

TEST(CadImportErrors, OptionsOutOfRangeNameTheField) {
  const auto with = [](auto set) {
    CadImportOptions options;
    set(options);
    return options;
  };
  EXPECT_NO_THROW(CadImportOptions().Check());
  const std::vector<std::pair<CadImportOptions, std::string>> cases = {
      {with([](auto& o) { o.sampling_step_mm = 0; }), "sampling_step_mm"},
      {with([](auto& o) { o.sampling_step_mm = std::nan(""); }), "sampling_step_mm"},
      {with([](auto& o) { o.linear_deflection_mm = -1; }), "linear_deflection_mm"},
      {with([](auto& o) { o.angular_deflection_rad = 0; }), "angular_deflection_rad"},
      {with([](auto& o) { o.timeout_s = 0; }), "timeout_s"},
  };
  for (const auto& c : cases) {
    const CadImportOptions& options = c.first;
    const std::string& field = c.second;
    ExpectError<OptionError>([&] { options.Check(); }, {"CadImportOptions." + field});
    ExpectError<OptionError>([&] { ReadCadModel("any.step", options); }, {field});
  }
  // A step so small the part would need billions of points is refused, not attempted.
  const test::TestDir dir("cad_import");
  const std::string path = dir.File("plate.step");
  WriteCadSolid(path, PlateWithHole(Eigen::Isometry3d::Identity()));
  ExpectError<InputError>(
      [&] { ReadCadModel(path, with([](auto& o) { o.sampling_step_mm = 1e-6; })); },
      {path, "sampling_step_mm", "increase the step"});
}

TEST(CadExportErrors, BadSolidsUnitsAndPathsAreInputErrors) {
  const test::TestDir dir("cad_export");
  const std::string path = dir.File("part.step");
  const CadSolid plate = PlateWithHole(Eigen::Isometry3d::Identity());
  ExpectError<InputError>([&] { WriteCadSolid(path, plate, "furlong"); },
                          {path, "'furlong'", "\"inch\""});
  ExpectError<InputError>([&] { WriteCadSolid(dir.File("part.obj"), plate); }, {"'.obj'"});
  ExpectError<InputError>([&] { WriteCadSolid(path, CadSolid{}); }, {path, "no primitives"});
  CadSolid first_subtracts = plate;
  std::swap(first_subtracts.primitives[0], first_subtracts.primitives[1]);
  ExpectError<InputError>([&] { WriteCadSolid(path, first_subtracts); }, {"primitives[0]"});
  CadSolid flat = plate;
  flat.primitives[0].size_mm.z() = 0;
  ExpectError<InputError>([&] { WriteCadSolid(path, flat); }, {"primitives[0].size_mm[2]"});
  CadSolid scaled = plate;
  scaled.primitives[1].part_from_primitive.linear() *= 2;
  ExpectError<InputError>([&] { WriteCadSolid(path, scaled); },
                          {"primitives[1].part_from_primitive", "rigid"});
  CadSolid everything = plate;
  everything.primitives[1].kind = CadPrimitive::kBox;
  everything.primitives[1].part_from_primitive =
      Eigen::Translation3d(-1, -1, -1) * Eigen::Isometry3d::Identity();
  everything.primitives[1].size_mm = Eigen::Vector3d(kX + 2, kY + 2, kZ + 2);
  ExpectError<InputError>([&] { WriteCadSolid(path, everything); }, {path, "whole solid"});
  EXPECT_FALSE(std::filesystem::exists(path)) << "nothing written on failure";
  const std::string no_folder = dir.File("no/such/folder/part.igs");
  ExpectError<FileError>([&] { WriteCadSolid(no_folder, plate); }, {no_folder});
}

}  // namespace
}  // namespace lasercell::localize
