// The Python module `lasercell` (its compiled part, lasercell._lasercell): bindings of the
// library API, NumPy arrays in and out (python/lasercell/__init__.py re-exports it).
#include "python/bindings/bindings.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_lasercell, m) {
  m.doc() = "lasercell: laser-triangulation metrology cell toolkit (millimetres, radians)";
  m.attr("__version__") = LASERCELL_VERSION;
  lasercell::python::BindErrors(m);
  lasercell::python::BindPointCloud(m);
  lasercell::python::BindFrameGraph(m);
  lasercell::python::BindCameraModel(m);
  lasercell::python::BindCalibration(m);
  lasercell::python::BindLaserPlane(m);
  lasercell::python::BindSpheres(m);
  lasercell::python::BindHandEye(m);
  lasercell::python::BindJoints(m);
  lasercell::python::BindSections(m);
  lasercell::python::BindTriangulation(m);
  lasercell::python::BindPeaks(m);
  lasercell::python::BindRegistration(m);
  lasercell::python::BindRegistrationStages(m);
  lasercell::python::BindMeshesAndParts(m);
  lasercell::python::BindLocalizeParts(m);
  lasercell::python::BindLocalizeJob(m);
}
