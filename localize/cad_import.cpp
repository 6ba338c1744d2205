#include "localize/cad_import.hpp"

#include <BRepAdaptor_Surface.hxx>
#include <BRepBuilderAPI_Sewing.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRepTools.hxx>
#include <BRepTopAdaptor_FClass2d.hxx>
#include <BRep_Tool.hxx>
#include <GProp_GProps.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Poly_Triangulation.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeFix_Solid.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopLoc_Location.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Builder.hxx>
#include <TopoDS_Compound.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <TopoDS_Shell.hxx>
#include <TopoDS_Solid.hxx>
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <gp_Pnt.hxx>
#include <gp_Pnt2d.hxx>
#include <gp_Vec.hxx>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/file_util.hpp"
#include "core/io/raw_record.hpp"
#include "core/isolated_call.hpp"
#include "localize/internal/occt_session.hpp"

namespace lasercell::localize {

void CadImportOptions::Check() const {
  if (!(timeout_s > 0) || !std::isfinite(timeout_s)) {
    throw OptionError("CadImportOptions.timeout_s must be positive and finite (s), got " +
                      std::to_string(timeout_s));
  }
  if (!(sampling_step_mm > 0) || !std::isfinite(sampling_step_mm)) {
    throw OptionError("CadImportOptions.sampling_step_mm must be positive and finite (mm), got " +
                      std::to_string(sampling_step_mm));
  }
  if (!(linear_deflection_mm > 0) || !std::isfinite(linear_deflection_mm)) {
    throw OptionError(
        "CadImportOptions.linear_deflection_mm must be positive and finite (mm), got " +
        std::to_string(linear_deflection_mm));
  }
  if (!(angular_deflection_rad > 0) || !std::isfinite(angular_deflection_rad)) {
    throw OptionError(
        "CadImportOptions.angular_deflection_rad must be positive and finite (rad), got " +
        std::to_string(angular_deflection_rad));
  }
}

namespace {

enum class CadFormat { kStep, kIges };

// More grid cells than this on one face means the step is far too small for the part.
constexpr double kMaxGridCellsPerFace = 5e7;

CadFormat FormatOf(const std::string& path) {
  const std::string ext = io::LowerExtension(path);
  if (ext == ".step" || ext == ".stp") return CadFormat::kStep;
  if (ext == ".iges" || ext == ".igs") return CadFormat::kIges;
  throw InputError(path + ": unknown CAD file extension '" + ext +
                   "'; expected .step or .stp (STEP) or .iges or .igs (IGES): export the part "
                   "in one of these formats");
}

// FileError for a missing, unreadable or directory path; InputError for an empty file (the
// IGES reader would accept it as a file with nothing in it).
void CheckReadable(const std::string& path, const char* format_name) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw FileError(path,
                    std::string("does not exist; give the path of a ") + format_name + " file");
  }
  if (std::filesystem::is_directory(path, ec)) {
    throw FileError(path, "is a directory, expected a file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, std::string("cannot open for reading: ") + std::strerror(errno));
  if (in.peek() == std::ifstream::traits_type::eof()) {
    throw InputError(path + ": is empty, expected a " + format_name +
                     " file; export the part again");
  }
}

const char* StatusName(IFSelect_ReturnStatus status) {
  switch (status) {
    case IFSelect_RetVoid:
      return "RetVoid (nothing read)";
    case IFSelect_RetDone:
      return "RetDone";
    case IFSelect_RetError:
      return "RetError (not a file of this format, or unreadable)";
    case IFSelect_RetFail:
      return "RetFail (syntax error, the file is not valid)";
    case IFSelect_RetStop:
      return "RetStop (reading stopped)";
  }
  return "unknown status";
}

// A length unit both formats can declare: our name, millimetres per unit, the names STEP files
// use (SI units as OpenCASCADE spells them with prefix, conversion-based units as written) and
// the IGES global-section unit flag (IGES 5.3, section 2.2.4.3, parameter 14).
struct LengthUnit {
  const char* name;
  double mm;
  std::array<const char*, 3> step_names;
  int iges_flag;
};

constexpr std::array<LengthUnit, 10> kLengthUnits = {{
    {"mm", 1.0, {"millimetre", "millimeter", "mm"}, 2},
    {"cm", 10.0, {"centimetre", "centimeter", "cm"}, 10},
    {"m", 1000.0, {"metre", "meter", "m"}, 6},
    {"km", 1e6, {"kilometre", "kilometer", "km"}, 7},
    {"um", 1e-3, {"micrometre", "micrometer", "micron"}, 9},
    {"inch", 25.4, {"inch", "inches", "in"}, 1},
    {"ft", 304.8, {"foot", "feet", "ft"}, 4},
    {"mile", 1609344.0, {"mile", "miles", "mi"}, 5},
    {"mil", 0.0254, {"mil", "mils", "thou"}, 8},
    {"microinch", 2.54e-5, {"microinch", "microinches", "uin"}, 11},
}};

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const LengthUnit* FindStepUnit(const std::string& name) {
  const std::string lower = Lower(name);
  for (const LengthUnit& unit : kLengthUnits) {
    for (const char* step_name : unit.step_names) {
      if (lower == step_name) return &unit;
    }
  }
  return nullptr;
}

const LengthUnit* FindIgesUnit(int flag) {
  for (const LengthUnit& unit : kLengthUnits) {
    if (unit.iges_flag == flag) return &unit;
  }
  return nullptr;
}

std::string UnsupportedUnitMessage(const std::string& path, const std::string& declared) {
  return path + ": declares the unknown or unsupported length unit '" + declared +
         "'; re-export the part in millimetres, inches or metres";
}

// The shape read from a file in millimetres, with the unit the file declared.
struct LoadedShape {
  TopoDS_Shape shape;
  std::string unit;
  double scale_to_mm = 1.0;
};

LoadedShape LoadStep(const std::string& path) {
  STEPControl_Reader reader;
  const IFSelect_ReturnStatus status = reader.ReadFile(path.c_str());
  if (status != IFSelect_RetDone) {
    throw InputError(path + ": not a readable STEP file (OpenCASCADE status " + StatusName(status) +
                     "); check that it is an ISO 10303-21 file (it starts with "
                     "'ISO-10303-21;') or export the part again");
  }
  LoadedShape loaded;
  if (reader.NbRootsForTransfer() == 0) {
    throw InputError(path +
                     ": holds no surfaces (no shape representation to translate): export the "
                     "part as a solid");
  }
  TColStd_SequenceOfAsciiString length_names, angle_names, solid_angle_names;
  reader.FileUnits(length_names, angle_names, solid_angle_names);
  if (length_names.IsEmpty()) {
    throw InputError(path +
                     ": declares no length unit (no GLOBAL_UNIT_ASSIGNED_CONTEXT); re-export the "
                     "part with its units");
  }
  for (int i = 1; i <= length_names.Length(); ++i) {
    const std::string declared = length_names.Value(i).ToCString();
    const LengthUnit* unit = FindStepUnit(declared);
    if (unit == nullptr) throw InputError(UnsupportedUnitMessage(path, declared));
    if (i == 1) {
      loaded.unit = unit->name;
      loaded.scale_to_mm = unit->mm;
    } else {
      loaded.unit += std::string(", ") + unit->name;
    }
  }
  reader.TransferRoots();
  loaded.shape = reader.OneShape();
  return loaded;
}

// IGES 5.3, section 2.1: the file starts with a Start-section record, 80 columns with 'S' in
// column 73. OpenCASCADE's reader accepts some text without it as an empty IGES file.
void CheckIgesStart(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string first;
  std::getline(in, first);
  if (first.size() < 73 || first[72] != 'S') {
    throw InputError(path +
                     ": not a readable IGES file (its first line is not a Start-section record "
                     "with 'S' in column 73); check that it is an IGES file or export the part "
                     "again");
  }
}

LoadedShape LoadIges(const std::string& path) {
  CheckIgesStart(path);
  IGESControl_Reader reader;
  const IFSelect_ReturnStatus status = reader.ReadFile(path.c_str());
  if (status != IFSelect_RetDone) {
    throw InputError(path + ": not a readable IGES file (OpenCASCADE status " + StatusName(status) +
                     "); check that it is an IGES file (80-column records, S/G/D/P/T in column "
                     "73) or export the part again");
  }
  const IGESData_GlobalSection& global = reader.IGESModel()->GlobalSection();
  // OpenCASCADE already resolved flag 3 ("named in parameter 15") to a flag when it knows the
  // name; a flag left at 3 or out of range is a unit it would silently take as millimetres.
  const LengthUnit* unit = FindIgesUnit(global.UnitFlag());
  if (unit == nullptr) {
    const Handle(TCollection_HAsciiString) name = global.UnitName();
    const std::string declared = name.IsNull() ? std::string() : name->ToCString();
    throw InputError(UnsupportedUnitMessage(
        path, declared.empty() ? "flag " + std::to_string(global.UnitFlag()) : declared));
  }
  LoadedShape loaded;
  loaded.unit = unit->name;
  loaded.scale_to_mm = unit->mm;
  if (reader.NbRootsForTransfer() == 0) {
    throw InputError(path +
                     ": holds no surfaces (no entity to translate): export the part as a "
                     "solid");
  }
  reader.TransferRoots();
  loaded.shape = reader.OneShape();
  return loaded;
}

// Gap between neighbouring faces that sewing closes, mm: exporters write trimmed surfaces
// whose edges meet to about 1e-3..1e-2 mm.
constexpr double kSewingToleranceMm = 0.01;

// IGES files from most CAD systems hold loose trimmed surfaces (entity 144), not solids: their
// face orientations follow each surface's parametrization, so "outward" is undefined until the
// faces are sewn into shells and each closed shell is made a solid oriented by its enclosed
// volume (ShapeFix_Solid::SolidFromShell). Open shells stay as sewn (consistently oriented, but
// the side is the file's). Shapes that already are solids are returned unchanged.
TopoDS_Shape SolidsFromLooseFaces(const TopoDS_Shape& shape) {
  if (TopExp_Explorer(shape, TopAbs_SOLID).More() || !TopExp_Explorer(shape, TopAbs_FACE).More()) {
    return shape;
  }
  BRepBuilderAPI_Sewing sewing(kSewingToleranceMm);
  sewing.Add(shape);
  sewing.Perform();
  const TopoDS_Shape sewn = sewing.SewedShape();
  if (sewn.IsNull()) return shape;
  TopoDS_Compound result;
  TopoDS_Builder builder;
  builder.MakeCompound(result);
  for (TopExp_Explorer it(sewn, TopAbs_SHELL); it.More(); it.Next()) {
    const TopoDS_Shell& shell = TopoDS::Shell(it.Current());
    if (BRep_Tool::IsClosed(shell)) {
      ShapeFix_Solid fix;
      builder.Add(result, fix.SolidFromShell(shell));
    } else {
      builder.Add(result, shell);
    }
  }
  for (TopExp_Explorer it(sewn, TopAbs_FACE, TopAbs_SHELL); it.More(); it.Next()) {
    builder.Add(result, it.Current());  // faces sewing left alone
  }
  return result;
}

// Outward unit normal of `face` at (u, v), or false where the parametrization degenerates
// (apex of a cone, pole of a sphere). Geom surfaces are oriented by dS/du x dS/dv; a face
// that uses its surface REVERSED has the opposite material side.
bool FaceNormal(const BRepAdaptor_Surface& surface, bool reversed, double u, double v, gp_Pnt& p,
                Eigen::Vector3d& normal) {
  gp_Vec du, dv;
  surface.D1(u, v, p, du, dv);
  const gp_Vec n = du.Crossed(dv);
  const double length = n.Magnitude();
  if (!(length > 1e-12 * std::max(1.0, du.Magnitude() * dv.Magnitude()))) return false;
  normal = Eigen::Vector3d(n.X(), n.Y(), n.Z()) / length;
  if (reversed) normal = -normal;
  return true;
}

// Length of the polyline through `segments` + 1 points of the curve t -> at(t), t in [t0, t1].
template <typename At>
double PolylineLength(At at, double t0, double t1, int segments) {
  double length = 0;
  gp_Pnt previous = at(t0);
  for (int i = 1; i <= segments; ++i) {
    const gp_Pnt next = at(t0 + (t1 - t0) * i / segments);
    length += previous.Distance(next);
    previous = next;
  }
  return length;
}

// Samples one face on a grid in its (u, v) box: rows of constant v spaced by ~step along the
// surface, and along each row points spaced by ~step along that row's iso-curve (so cones and
// spheres keep the density where a circle shrinks). Cell centres only, kept when the 2D
// classifier puts them inside the trimmed face: every point lies on the exact surface.
void SampleFace(const TopoDS_Face& face, double step, const std::string& path, PointCloud& out) {
  const BRepAdaptor_Surface surface(face, true);
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  double u0 = 0, u1 = 0, v0 = 0, v1 = 0;
  BRepTools::UVBounds(face, u0, u1, v0, v1);
  if (!(u1 > u0) || !(v1 > v0)) return;
  constexpr int kSegments = 64;
  constexpr int kProbes = 5;
  double v_length = 0;
  for (int k = 0; k < kProbes; ++k) {
    const double u = u0 + (u1 - u0) * (k + 0.5) / kProbes;
    v_length = std::max(
        v_length, PolylineLength([&](double v) { return surface.Value(u, v); }, v0, v1, kSegments));
  }
  const double rows = std::ceil(v_length / step);
  if (rows > kMaxGridCellsPerFace) {
    throw InputError(path + ": a face is " + std::to_string(v_length) +
                     " mm long; CadImportOptions.sampling_step_mm = " + std::to_string(step) +
                     " would sample it with too many points: increase the step");
  }
  const int nv = std::max(1, static_cast<int>(rows));
  const BRepTopAdaptor_FClass2d classifier(face, 1e-9);
  for (int j = 0; j < nv; ++j) {
    const double v = v0 + (v1 - v0) * (j + 0.5) / nv;
    const double u_length =
        PolylineLength([&](double u) { return surface.Value(u, v); }, u0, u1, kSegments);
    const double cells = std::ceil(u_length / step);
    if (cells * nv > kMaxGridCellsPerFace) {
      throw InputError(path + ": CadImportOptions.sampling_step_mm = " + std::to_string(step) +
                       " samples a face of this part with more than " +
                       std::to_string(kMaxGridCellsPerFace) + " points: increase the step");
    }
    const int nu = std::max(1, static_cast<int>(cells));
    for (int i = 0; i < nu; ++i) {
      const double u = u0 + (u1 - u0) * (i + 0.5) / nu;
      if (classifier.Perform(gp_Pnt2d(u, v)) != TopAbs_IN) continue;
      gp_Pnt p;
      Eigen::Vector3d normal;
      if (!FaceNormal(surface, reversed, u, v, p, normal)) continue;
      out.positions.emplace_back(p.X(), p.Y(), p.Z());
      out.normals.push_back(normal);
    }
  }
}

// Appends the triangulation of one face: its nodes (moved by the face's location), triangles
// counter-clockwise seen from outside, and vertex normals from the exact surface at the nodes'
// (u, v); where the surface normal degenerates, the mean of the adjacent triangles' normals.
void AppendFaceMesh(const TopoDS_Face& face, std::size_t face_index, const std::string& path,
                    TriangleMesh& mesh) {
  TopLoc_Location location;
  const Handle(Poly_Triangulation) triangulation = BRep_Tool::Triangulation(face, location);
  if (triangulation.IsNull() || triangulation->NbTriangles() == 0) {
    throw InputError(path + ": face " + std::to_string(face_index) +
                     " could not be tessellated (broken or degenerate surface); repair the "
                     "part in the CAD system or export it again");
  }
  const bool reversed = face.Orientation() == TopAbs_REVERSED;
  const gp_Trsf transform = location.Transformation();
  const int base = static_cast<int>(mesh.vertices.size());
  const int nodes = triangulation->NbNodes();
  for (int i = 1; i <= nodes; ++i) {
    const gp_Pnt p = triangulation->Node(i).Transformed(transform);
    mesh.vertices.positions.emplace_back(p.X(), p.Y(), p.Z());
  }
  std::vector<Eigen::Vector3d> accumulated(static_cast<std::size_t>(nodes),
                                           Eigen::Vector3d::Zero());
  for (int t = 1; t <= triangulation->NbTriangles(); ++t) {
    int a = 0, b = 0, c = 0;
    triangulation->Triangle(t).Get(a, b, c);
    if (reversed) std::swap(b, c);
    const Eigen::Vector3i tri(base + a - 1, base + b - 1, base + c - 1);
    mesh.faces.push_back(tri);
    const auto& v = mesh.vertices.positions;
    const Eigen::Vector3d n = (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]);
    for (int k : {a, b, c}) accumulated[static_cast<std::size_t>(k - 1)] += n;
  }
  const BRepAdaptor_Surface surface(face, false);
  for (int i = 1; i <= nodes; ++i) {
    Eigen::Vector3d normal = accumulated[static_cast<std::size_t>(i - 1)];
    gp_Pnt p;
    Eigen::Vector3d exact;
    if (triangulation->HasUVNodes()) {
      const gp_Pnt2d uv = triangulation->UVNode(i);
      if (FaceNormal(surface, reversed, uv.X(), uv.Y(), p, exact)) normal = exact;
    }
    const double length = normal.norm();
    mesh.vertices.normals.push_back(length > 0 ? Eigen::Vector3d(normal / length)
                                               : Eigen::Vector3d::UnitZ());
  }
}

CadModel BuildModel(const TopoDS_Shape& shape, const CadImportOptions& options,
                    const std::string& path) {
  CadModel model;
  TopTools_IndexedMapOfShape solids, shells, faces;
  TopExp::MapShapes(shape, TopAbs_SOLID, solids);
  TopExp::MapShapes(shape, TopAbs_SHELL, shells);
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  model.solids = static_cast<std::size_t>(solids.Extent());
  model.shells = static_cast<std::size_t>(shells.Extent());
  model.faces = static_cast<std::size_t>(faces.Extent());
  if (model.faces == 0) {
    throw InputError(path +
                     ": holds no surfaces (no solid, shell or face; only curves or points): "
                     "export the part as a solid");
  }
  GProp_GProps area;
  BRepGProp::SurfaceProperties(shape, area);
  model.surface_area_mm2 = area.Mass();

  // Our own tessellation at the requested deflection, not one stored in the file.
  BRepTools::Clean(shape);
  const BRepMesh_IncrementalMesh mesher(shape, options.linear_deflection_mm, false,
                                        options.angular_deflection_rad, false);
  if (!mesher.IsDone()) {
    throw InputError(path +
                     ": OpenCASCADE could not tessellate the part; repair it in the CAD system "
                     "or export it again");
  }
  model.mesh.vertices.positions.reserve(static_cast<std::size_t>(faces.Extent()) * 64);
  for (int i = 1; i <= faces.Extent(); ++i) {
    const TopoDS_Face face = TopoDS::Face(faces.FindKey(i));
    AppendFaceMesh(face, static_cast<std::size_t>(i), path, model.mesh);
    SampleFace(face, options.sampling_step_mm, path, model.samples);
  }
  return model;
}

// A CadModel as bytes, to come back from the child process ReadCadModel reads in (both ends
// are the same program on the same machine).
std::string ModelToBytes(const CadModel& m) {
  io::RawWriter out;
  out.PutArray(m.mesh.vertices.positions);
  out.PutArray(m.mesh.vertices.normals);
  out.PutArray(m.mesh.faces);
  out.PutArray(m.samples.positions);
  out.PutArray(m.samples.normals);
  out.PutString(m.format);
  out.PutString(m.source_unit);
  for (const double v : {m.scale_to_mm, m.surface_area_mm2}) out.Put(v);
  for (const std::size_t v : {m.solids, m.shells, m.faces}) out.Put(v);
  return std::move(out.bytes());
}

CadModel ModelFromBytes(const std::string& bytes) {
  io::RawReader in(bytes, [](const std::string& problem) {
    throw InternalError("CAD model from the reader process: " + problem);
  });
  CadModel m;
  m.mesh.vertices.positions = in.GetArray<Eigen::Vector3d>("mesh positions");
  m.mesh.vertices.normals = in.GetArray<Eigen::Vector3d>("mesh normals");
  m.mesh.faces = in.GetArray<Eigen::Vector3i>("faces");
  m.samples.positions = in.GetArray<Eigen::Vector3d>("sample positions");
  m.samples.normals = in.GetArray<Eigen::Vector3d>("sample normals");
  m.format = in.GetString("format");
  m.source_unit = in.GetString("source unit");
  m.scale_to_mm = in.Get<double>("scale");
  m.surface_area_mm2 = in.Get<double>("area");
  m.solids = in.Get<std::size_t>("solids");
  m.shells = in.Get<std::size_t>("shells");
  m.faces = in.Get<std::size_t>("face count");
  if (!in.AtEnd()) in.Fail("bytes after the model");
  return m;
}

CadModel ReadCadModelHere(const std::string& path, const CadImportOptions& options,
                          CadFormat format) {
  const char* format_name = format == CadFormat::kStep ? "STEP" : "IGES";
  try {
    LoadedShape loaded = format == CadFormat::kStep ? LoadStep(path) : LoadIges(path);
    if (loaded.shape.IsNull()) {
      throw InputError(path +
                       ": holds no surfaces (nothing could be translated): export the "
                       "part as a solid");
    }
    CadModel model = BuildModel(SolidsFromLooseFaces(loaded.shape), options, path);
    model.format = format == CadFormat::kStep ? "step" : "iges";
    model.source_unit = loaded.unit;
    model.scale_to_mm = loaded.scale_to_mm;
    return model;
  } catch (const Standard_Failure& failure) {
    throw InputError(path + ": OpenCASCADE failed reading this " + format_name + " file (" +
                     internal::DescribeFailure(failure) +
                     "); repair the part in the CAD system or export it again");
  }
}

}  // namespace

// OpenCASCADE's translators trust the entity references of the file: a damaged file (a shell
// naming a face that is not there) makes them dereference null inside libTKIGES/libTKSTEP. The
// whole read runs in a child process (core/isolated_call.hpp), under the session lock so no
// other thread is inside OpenCASCADE when it forks; a crash there is this file's error.
CadModel ReadCadModel(const std::string& path, const CadImportOptions& options) {
  options.Check();
  const CadFormat format = FormatOf(path);
  const char* format_name = format == CadFormat::kStep ? "STEP" : "IGES";
  CheckReadable(path, format_name);
  IsolatedOutcome outcome;
  {
    const internal::OcctSession session;
    outcome = RunIsolated([&] { return ModelToBytes(ReadCadModelHere(path, options, format)); },
                          options.timeout_s);
  }
  switch (outcome.kind) {
    case IsolatedOutcome::Kind::kReturned:
      return ModelFromBytes(outcome.bytes);
    case IsolatedOutcome::Kind::kInputError:
      throw InputError(outcome.message);
    case IsolatedOutcome::Kind::kOtherError:
      throw InternalError(path + ": reading this " + format_name +
                          " file failed: " + outcome.message);
    case IsolatedOutcome::Kind::kTimedOut:
      throw InputError(path + ": OpenCASCADE was still reading this " + format_name +
                       " file after " + FormatDouble(options.timeout_s) +
                       " s (CadImportOptions.timeout_s) and was stopped; the file is damaged or "
                       "far larger than a part: export the part again");
    case IsolatedOutcome::Kind::kCrashed:
      break;
  }
  if (IsFaultSignal(outcome.signal)) {
    throw InputError(path + ": OpenCASCADE crashed reading this " + format_name + " file (signal " +
                     std::to_string(outcome.signal) +
                     "): it is damaged or refers to entities it does not hold; export the part "
                     "again from the CAD system");
  }
  throw InternalError(path + ": the process reading this " + format_name + " file ended " +
                      (outcome.signal != 0 ? "by signal " + std::to_string(outcome.signal)
                                           : std::string("without a result")));
}

}  // namespace lasercell::localize
