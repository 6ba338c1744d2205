#include "localize/cad_export.hpp"

#include <stdlib.h>  // mkstemp (POSIX)
#include <unistd.h>

#include <APIHeaderSection_MakeHeader.hxx>
#include <BRepAlgoAPI_Cut.hxx>
#include <BRepAlgoAPI_Fuse.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Writer.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <StepBasic_Product.hxx>
#include <StepData_StepModel.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Shape.hxx>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <gp_Ax2.hxx>
#include <gp_Dir.hxx>
#include <gp_Pnt.hxx>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "localize/internal/occt_session.hpp"

namespace lasercell::localize {
namespace {

enum class CadFormat { kStep, kIges };

CadFormat FormatOf(const std::string& path) {
  const std::string ext = io::LowerExtension(path);
  if (ext == ".step" || ext == ".stp") return CadFormat::kStep;
  if (ext == ".iges" || ext == ".igs") return CadFormat::kIges;
  throw InputError(path + ": unknown CAD file extension '" + ext +
                   "'; write .step or .stp (STEP) or .iges or .igs (IGES)");
}

// The unit's spelling for OpenCASCADE's STEP and IGES writers.
struct UnitNames {
  const char* step;
  const char* iges;
};

UnitNames UnitNamesOf(const std::string& unit, const std::string& path) {
  if (unit == "mm") return {"MM", "MM"};
  if (unit == "inch") return {"INCH", "IN"};
  if (unit == "m") return {"M", "M"};
  throw InputError(path + ": unknown length unit '" + unit +
                   "' to write the CAD file in; use \"mm\", \"inch\" or \"m\"");
}

void CheckPrimitive(const CadPrimitive& primitive, std::size_t index, const std::string& path) {
  const std::string what = path + ": CadSolid.primitives[" + std::to_string(index) + "]";
  if (primitive.kind != CadPrimitive::kBox && primitive.kind != CadPrimitive::kCylinder) {
    throw InputError(what + ".kind is neither kBox nor kCylinder");
  }
  const int sizes = primitive.kind == CadPrimitive::kBox ? 3 : 2;
  for (int k = 0; k < sizes; ++k) {
    if (!(primitive.size_mm[k] > 0) || !std::isfinite(primitive.size_mm[k])) {
      throw InputError(what + ".size_mm[" + std::to_string(k) +
                       "] must be positive and finite (mm), got " +
                       std::to_string(primitive.size_mm[k]));
    }
  }
  const Eigen::Matrix3d r = primitive.part_from_primitive.linear();
  const bool rigid = primitive.part_from_primitive.matrix().allFinite() &&
                     (r.transpose() * r - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
                     r.determinant() > 0;
  if (!rigid) {
    throw InputError(what +
                     ".part_from_primitive must be a rigid transform (orthonormal rotation, "
                     "determinant +1, finite translation)");
  }
}

// The primitive's frame as an OpenCASCADE axis system (origin, z axis, x axis) in the part.
gp_Ax2 AxesOf(const Eigen::Isometry3d& part_from_primitive) {
  const Eigen::Vector3d o = part_from_primitive.translation();
  const Eigen::Vector3d z = part_from_primitive.linear().col(2);
  const Eigen::Vector3d x = part_from_primitive.linear().col(0);
  return gp_Ax2(gp_Pnt(o.x(), o.y(), o.z()), gp_Dir(z.x(), z.y(), z.z()),
                gp_Dir(x.x(), x.y(), x.z()));
}

TopoDS_Shape MakePrimitive(const CadPrimitive& primitive) {
  const gp_Ax2 axes = AxesOf(primitive.part_from_primitive);
  const Eigen::Vector3d& s = primitive.size_mm;
  if (primitive.kind == CadPrimitive::kBox) {
    return BRepPrimAPI_MakeBox(axes, s.x(), s.y(), s.z()).Shape();
  }
  return BRepPrimAPI_MakeCylinder(axes, s.x(), s.y()).Shape();
}

// Union of the additive primitives minus the subtractive ones, in order. SimplifyResult merges
// the coplanar / co-cylindrical pieces the Boolean operations split faces into.
TopoDS_Shape BuildSolid(const CadSolid& solid, const std::string& path) {
  TopoDS_Shape result = MakePrimitive(solid.primitives.front());
  for (std::size_t i = 1; i < solid.primitives.size(); ++i) {
    const CadPrimitive& primitive = solid.primitives[i];
    const TopoDS_Shape tool = MakePrimitive(primitive);
    std::ostringstream errors;
    if (primitive.subtract) {
      BRepAlgoAPI_Cut cut(result, tool);
      if (cut.HasErrors()) cut.DumpErrors(errors);
      if (!cut.HasErrors()) cut.SimplifyResult();
      if (!cut.HasErrors()) result = cut.Shape();
    } else {
      BRepAlgoAPI_Fuse fuse(result, tool);
      if (fuse.HasErrors()) fuse.DumpErrors(errors);
      if (!fuse.HasErrors()) fuse.SimplifyResult();
      if (!fuse.HasErrors()) result = fuse.Shape();
    }
    if (!errors.str().empty()) {
      throw InputError(path + ": the Boolean operation with CadSolid.primitives[" +
                       std::to_string(i) + "] failed (" + errors.str() +
                       "); move the primitive so its faces do not just touch the solid");
    }
  }
  if (result.IsNull() || !TopExp_Explorer(result, TopAbs_FACE).More()) {
    throw InputError(path +
                     ": the subtractive primitives remove the whole solid; nothing to "
                     "write");
  }
  return result;
}

// STEP: OpenCASCADE writes only to a named file, so to a temporary one first, whose bytes then
// go through the atomic write. The product is named after the file and the header carries a
// fixed time stamp (OpenCASCADE's defaults are a per-process counter and the wall clock), so
// the bytes depend on the solid and the unit alone.
std::string StepBytes(const TopoDS_Shape& shape, const UnitNames& unit, const std::string& path) {
  internal::OcctSession::SetStatic("write.step.unit", unit.step);
  internal::OcctSession::SetStatic("write.step.schema", "AP214IS");
  STEPControl_Writer writer;
  if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone) {
    throw InputError(path + ": OpenCASCADE could not translate the solid to STEP");
  }
  const Handle(StepData_StepModel) model = writer.Model();
  std::string stem = std::filesystem::path(path).stem().string();
  if (stem.empty()) stem = "part";
  const Handle(TCollection_HAsciiString) product = new TCollection_HAsciiString(stem.c_str());
  for (Standard_Integer i = 1; i <= model->NbEntities(); ++i) {
    const Handle(StepBasic_Product) p = Handle(StepBasic_Product)::DownCast(model->Value(i));
    if (p.IsNull()) continue;
    p->SetId(product);
    p->SetName(product);
  }
  APIHeaderSection_MakeHeader header(model);
  header.SetTimeStamp(new TCollection_HAsciiString("1970-01-01T00:00:00"));
  std::string temp = (std::filesystem::temp_directory_path() / "lasercell-cad-XXXXXX").string();
  const int fd = mkstemp(temp.data());
  if (fd < 0) throw FileError(temp, "cannot create a temporary file for the STEP writer");
  ::close(fd);
  const IFSelect_ReturnStatus status = writer.Write(temp.c_str());
  std::string bytes;
  if (status == IFSelect_RetDone) {
    try {
      bytes = io::ReadFileBytes(temp);
    } catch (...) {
      std::remove(temp.c_str());
      throw;
    }
  }
  std::remove(temp.c_str());
  if (status != IFSelect_RetDone || bytes.empty()) {
    throw FileError(path, "OpenCASCADE's STEP writer failed (temporary file " + temp + ")");
  }
  return bytes;
}

// IGES 5.3 with B-rep solid entities (type 186, write.iges.brep.mode = 1), so the file keeps
// the solid and its face orientations rather than loose trimmed surfaces.
std::string IgesBytes(const TopoDS_Shape& shape, const UnitNames& unit, const std::string& path) {
  internal::OcctSession::SetStatic("write.iges.brep.mode", 1);
  IGESControl_Writer writer(unit.iges, 1);
  if (!writer.AddShape(shape)) {
    throw InputError(path + ": OpenCASCADE could not translate the solid to IGES");
  }
  writer.ComputeModel();
  std::ostringstream out;
  if (!writer.Write(out)) throw FileError(path, "OpenCASCADE's IGES writer failed");
  return out.str();
}

}  // namespace

void WriteCadSolid(const std::string& path, const CadSolid& solid, const std::string& unit) {
  const CadFormat format = FormatOf(path);
  const UnitNames names = UnitNamesOf(unit, path);
  if (solid.primitives.empty()) throw InputError(path + ": CadSolid has no primitives");
  if (solid.primitives.front().subtract) {
    throw InputError(path +
                     ": CadSolid.primitives[0] subtracts from nothing; start with an "
                     "additive primitive");
  }
  for (std::size_t i = 0; i < solid.primitives.size(); ++i) {
    CheckPrimitive(solid.primitives[i], i, path);
  }
  std::string bytes;
  try {
    const internal::OcctSession session;
    const TopoDS_Shape shape = BuildSolid(solid, path);
    bytes =
        format == CadFormat::kStep ? StepBytes(shape, names, path) : IgesBytes(shape, names, path);
  } catch (const Standard_Failure& failure) {
    throw InputError(path + ": OpenCASCADE failed building or writing the solid (" +
                     internal::DescribeFailure(failure) + "); check the primitives' sizes");
  }
  io::WriteFileAtomically(path, bytes);
}

}  // namespace lasercell::localize
