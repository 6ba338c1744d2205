// Camera calibration from Python: boards (calib/board.hpp), board detection in image files
// (calib/camera_calibration.hpp, the detector cascade of calib/target_detection.hpp) and the
// intrinsics solve (calib/intrinsics.hpp) as `lasercell calibrate camera` runs them. Detections
// may also come from the caller's own detector as arrays (BoardView). The result carries the
// CameraModel and the calibration document as a dict.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "calib/board.hpp"
#include "calib/camera_calibration.hpp"
#include "calib/intrinsics.hpp"
#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"

namespace lasercell::python {
namespace {

using calib::BoardSpec;
using calib::BoardView;
using calib::CalibrationImages;
using calib::IntrinsicsResult;

BoardView MakeView(const std::string& name, const py::handle& corners_px,
                   const py::handle& corner_ids) {
  BoardView view;
  view.name = name;
  const py::array a = py::array::ensure(corners_px);
  if (!a || a.ndim() != 2 || a.shape(1) != 2) {
    ThrowInput("corners_px: expected shape (K, 2) of pixel coordinates");
  }
  const std::vector<double> flat =
      ToDoubles(a.attr("reshape")(-1), "corners_px", 2 * static_cast<std::size_t>(a.shape(0)));
  for (std::size_t i = 0; i + 1 < flat.size(); i += 2) {
    view.corners_px.emplace_back(flat[i], flat[i + 1]);
  }
  const std::vector<std::int32_t> ids = ToInt32s(corner_ids, "corner_ids", view.corners_px.size());
  view.corner_ids.assign(ids.begin(), ids.end());
  return view;
}

void BindBoard(py::module_& m) {
  py::class_<BoardSpec>(m, "Board", LC_DOC(calib_BoardSpec))
      .def(py::init(&calib::ParseBoardSpec), py::arg("spec"),
           "'chessboard:COLSxROWS:SQUARE_MM' (inner corners) or "
           "'charuco:SXxSY:SQUARE_MM:MARKER_MM[:DICT]' (squares), as --board takes it.")
      .def_property_readonly(
          "corners_mm", [](const BoardSpec& b) { return RowsArray(b.Corners()); },
          "(K, 3) corner positions in the board frame by id, mm (z = 0).")
      .def_property_readonly("num_corners", &BoardSpec::NumCorners,
                             LC_DOC(calib_BoardSpec_NumCorners))
      .def("__str__", &BoardSpec::ToString, LC_DOC(calib_BoardSpec_ToString))
      .def("__repr__", [](const BoardSpec& b) { return "<lasercell.Board " + b.ToString() + ">"; });

  py::class_<BoardView>(m, "BoardView", LC_DOC(calib_BoardView))
      .def(py::init(&MakeView), py::arg("name"), py::arg("corners_px"), py::arg("corner_ids"),
           "corners_px (K, 2), px; corner_ids (K,): the Board's corner id of each.")
      .def_readonly("name", &BoardView::name, LC_DOC(calib_BoardView_name))
      .def_property_readonly(
          "corners_px", [](const BoardView& v) { return RowsArray(v.corners_px); },
          "(K, 2): " LC_DOC(calib_BoardView_corners_px))
      .def_property_readonly(
          "corner_ids",
          [](const BoardView& v) {
            return py::array_t<int>(static_cast<py::ssize_t>(v.corner_ids.size()),
                                    v.corner_ids.data());
          },
          "(K,): " LC_DOC(calib_BoardView_corner_ids));
}

void BindDetections(py::module_& m) {
  py::class_<CalibrationImages, std::shared_ptr<CalibrationImages>>(
      m, "BoardDetections", "The board found (or not) in each image file.")
      .def_readonly("views", &CalibrationImages::views, "One BoardView per usable image.")
      .def_readonly("width", &CalibrationImages::width, LC_DOC(calib_CalibrationImages_width))
      .def_readonly("height", &CalibrationImages::height, LC_DOC(calib_CalibrationImages_height))
      .def_property_readonly(
          "images",
          [](const CalibrationImages& c) {
            py::list out;
            for (const calib::CalibrationImage& i : c.images) {
              out.append(py::make_tuple(i.path, i.detection.found(), i.detection.detector,
                                        i.rejection.empty() ? i.detection.message : i.rejection));
            }
            return out;
          },
          "[(path, found, detector, message)] per image file.");
  m.def(
      "detect_boards",
      [](const std::vector<std::string>& paths, const BoardSpec& board,
         const py::object& progress) {
        const ProgressCallback report = ToProgress(progress);
        py::gil_scoped_release release;
        return std::make_shared<CalibrationImages>(
            calib::DetectCalibrationImages(paths, board, nullptr, report));
      },
      py::arg("paths"), py::arg("board"), py::arg("progress") = py::none(),
      LC_DOC(calib_DetectCalibrationImages) " In Python: unreadable files are reported in "
      ".images, not raised; progress(stage, fraction) may raise to stop.");
}

void BindResult(py::module_& m) {
  py::class_<IntrinsicsResult, std::shared_ptr<IntrinsicsResult>>(m, "IntrinsicsResult",
                                                                  "A camera calibration.")
      .def_readonly("camera", &IntrinsicsResult::camera, LC_DOC(calib_IntrinsicsResult_camera))
      .def_readonly("converged", &IntrinsicsResult::converged,
                    LC_DOC(calib_IntrinsicsResult_converged))
      .def_readonly("rms_px", &IntrinsicsResult::rms_px, LC_DOC(calib_IntrinsicsResult_rms_px))
      .def_readonly("residual_sigma_px", &IntrinsicsResult::residual_sigma_px,
                    LC_DOC(calib_IntrinsicsResult_residual_sigma_px))
      .def_readonly("num_corners", &IntrinsicsResult::num_corners,
                    LC_DOC(calib_IntrinsicsResult_num_corners))
      .def_readonly("num_outliers", &IntrinsicsResult::num_outliers,
                    LC_DOC(calib_IntrinsicsResult_num_outliers))
      .def_readonly("intrinsic_names", &IntrinsicsResult::intrinsic_names,
                    LC_DOC(calib_IntrinsicsResult_intrinsic_names))
      .def_readonly("intrinsics_sigma", &IntrinsicsResult::intrinsics_sigma,
                    LC_DOC(calib_IntrinsicsResult_intrinsics_sigma))
      .def_readonly("warnings", &IntrinsicsResult::warnings,
                    LC_DOC(calib_IntrinsicsResult_warnings))
      .def("summary", &IntrinsicsResult::Summary, LC_DOC(calib_IntrinsicsResult_Summary))
      .def("rejection_reason", &IntrinsicsResult::RejectionReason,
           LC_DOC(calib_IntrinsicsResult_RejectionReason));
}

}  // namespace

void BindCalibration(py::module_& m) {
  BindBoard(m);
  BindDetections(m);
  BindResult(m);
  m.def(
      "calibrate_intrinsics",
      [](const std::vector<BoardView>& views, const BoardSpec& board, int width, int height,
         const std::string& model, bool fix_aspect, bool board_warp, bool fall_back_to_opencv5,
         double outlier_sigma, int threads) {
        calib::IntrinsicsOptions options;
        options.model = calib::ParseLensModelKind(model, "model");
        options.fix_aspect_ratio = fix_aspect;
        options.estimate_board_warp = board_warp;
        options.outlier_threshold_sigma = outlier_sigma;
        options.threads = threads;
        options.Check();
        py::gil_scoped_release release;
        return std::make_shared<IntrinsicsResult>(
            fall_back_to_opencv5
                ? calib::CalibrateIntrinsicsFallingBackToOpencv5(views, board, width, height,
                                                                 options)
                : calib::CalibrateIntrinsics(views, board, width, height, options));
      },
      py::arg("views"), py::arg("board"), py::arg("width"), py::arg("height"),
      py::arg("model") = "opencv8", py::arg("fix_aspect") = false, py::arg("board_warp") = false,
      py::arg("fall_back_to_opencv5") = false, py::arg("outlier_sigma") = 4.0,
      py::arg("threads") = 1,
      R"doc(Camera intrinsics (a mrcal lens model, Ceres) from board views, as
`lasercell calibrate camera` solves them.

views: BoardViews (detect_boards(...).views, or your own detections). model: 'opencv8',
'opencv5' or 'splined'. fall_back_to_opencv5: refit OPENCV8 as OPENCV5 when it folds over
inside the imager (the CLI's default model does). Raises InputError when fewer than 3 views are
usable; a calibration that must not be used says why in rejection_reason().)doc");
  m.def(
      "camera_calibration_dict",
      [](const IntrinsicsResult& result, const BoardSpec& board, const CalibrationImages& images,
         const std::string& model, bool fix_aspect, bool board_warp, double outlier_sigma) {
        return JsonToPython(calib::CameraCalibrationJson(
            result, board, images, {model, fix_aspect, board_warp, outlier_sigma}));
      },
      py::arg("result"), py::arg("board"), py::arg("detections"), py::arg("model") = "opencv8",
      py::arg("fix_aspect") = false, py::arg("board_warp") = false, py::arg("outlier_sigma") = 4.0,
      "The lasercell.camera_calibration document `calibrate camera --json` writes, as a dict.");
}

}  // namespace lasercell::python
