// IGES files of loose trimmed surfaces (entity 144, what most CAD systems export as IGES), whose
// face orientations are whatever the exporter's surfaces say. Written here with OpenCASCADE
// directly, since WriteCadSolid always writes B-rep solids.
#include <gtest/gtest.h>

#include <BRepAlgoAPI_Cut.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <BRepPrimAPI_MakeCylinder.hxx>
#include <Eigen/Core>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Writer.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_SequenceOfPrinters.hxx>
#include <TopoDS_Shape.hxx>
#include <algorithm>
#include <cmath>
#include <gp_Ax2.hxx>
#include <sstream>
#include <string>

#include "localize/cad_import.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::localize {
namespace {

// A 40 x 30 x 5 mm plate with a radius-6 through-hole at (20, 15), as IGES trimmed surfaces;
// `reversed` flips every face, so the file's normals all point into the material.
std::string LooseFacePlateIges(bool reversed) {
  IGESControl_Controller::Init();
  Message_SequenceOfPrinters& printers = Message::DefaultMessenger()->ChangePrinters();
  const Message_SequenceOfPrinters saved = printers;
  printers.Clear();  // the writer prints statistics otherwise
  const TopoDS_Shape box = BRepPrimAPI_MakeBox(gp_Pnt(0, 0, 0), 40, 30, 5).Shape();
  const TopoDS_Shape hole =
      BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(20, 15, -1), gp_Dir(0, 0, 1)), 6, 7).Shape();
  BRepAlgoAPI_Cut cut(box, hole);
  cut.SimplifyResult();
  const TopoDS_Shape plate = reversed ? cut.Shape().Reversed() : cut.Shape();
  Interface_Static::SetIVal("write.iges.brep.mode", 0);
  IGESControl_Writer writer("MM", 0);
  writer.AddShape(plate);
  writer.ComputeModel();
  std::ostringstream out;
  writer.Write(out);
  printers = saved;
  return out.str();
}

TEST(CadLooseFaces, TrimmedSurfaceIgesIsSewnIntoAnOutwardSolid) {
  const test::TestDir dir("cad_loose_faces");
  for (const bool reversed : {false, true}) {
    SCOPED_TRACE(reversed ? "inward faces" : "outward faces");
    const std::string path = dir.File(reversed ? "inward.igs" : "outward.igs");
    const std::string text = LooseFacePlateIges(reversed);
    ASSERT_NE(text.find("     144"), std::string::npos) << "trimmed surfaces in the file";
    ASSERT_EQ(text.find("     186"), std::string::npos) << "no B-rep solid entity";
    test::Spit(path, text);
    const CadModel model = ReadCadModel(path);
    EXPECT_EQ(model.solids, 1u);
    EXPECT_EQ(model.faces, 7u);
    // Outward: away from the plate's centre on the outer faces, toward the axis on the hole.
    std::size_t inward = 0, hole = 0;
    for (std::size_t i = 0; i < model.samples.size(); ++i) {
      const Eigen::Vector3d& p = model.samples.positions[i];
      const Eigen::Vector3d& n = model.samples.normals[i];
      const double radial = std::hypot(p.x() - 20, p.y() - 15);
      const bool on_wall = std::abs(radial - 6) < 1e-6 && p.z() > 1e-6 && p.z() < 5 - 1e-6;
      const Eigen::Vector3d away = on_wall ? Eigen::Vector3d(20 - p.x(), 15 - p.y(), 0)
                                           : Eigen::Vector3d(p - Eigen::Vector3d(20, 15, 2.5));
      hole += on_wall ? 1 : 0;
      if (n.dot(away) <= 0) ++inward;
    }
    EXPECT_GT(hole, 100u);
    EXPECT_EQ(inward, 0u) << "of " << model.samples.size();
    double volume = 0;  // divergence theorem: positive when the mesh faces point outward
    const auto& v = model.mesh.vertices.positions;
    for (const Eigen::Vector3i& f : model.mesh.faces)
      volume += v[f[0]].dot(v[f[1]].cross(v[f[2]])) / 6;
    EXPECT_NEAR(volume, 40 * 30 * 5 - 3.14159265358979 * 36 * 5, 10.0);
  }
}

}  // namespace
}  // namespace lasercell::localize
