// Laser peaks from raw stripe images (triangulation/peak_detection.hpp): lasercell.detect_peaks
// takes a (H, W) uint8 or uint16 NumPy image without copying it (any row stride, contiguous
// pixels within a row) and returns one subpixel peak per column with its status.
#include <pybind11/stl.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "docstrings.hpp"  // generated from the headers' /// comments
#include "python/bindings/bindings.hpp"
#include "triangulation/peak_detection.hpp"

namespace lasercell::python {
namespace {

using triangulation::PeakDetectionResult;
using ResultPtr = std::shared_ptr<PeakDetectionResult>;

template <typename Pixel>
triangulation::ImageView<Pixel> View(const py::array& image) {
  if (image.strides(1) != static_cast<py::ssize_t>(sizeof(Pixel)) ||
      image.strides(0) % static_cast<py::ssize_t>(sizeof(Pixel)) != 0 || image.strides(0) <= 0) {
    ThrowInput(
        "image: the pixels of a row must be contiguous and rows must follow each other "
        "(C order, or a row slice of one); pass np.ascontiguousarray(image)");
  }
  triangulation::ImageView<Pixel> view;
  view.data = static_cast<const Pixel*>(image.data());
  view.height = static_cast<int>(image.shape(0));
  view.width = static_cast<int>(image.shape(1));
  view.stride = static_cast<int>(image.strides(0) / static_cast<py::ssize_t>(sizeof(Pixel)));
  return view;
}

ResultPtr Detect(const py::array& image, const std::string& estimator, double min_height,
                 double cog_threshold_fraction, double ambiguity_ratio, double saturation_level,
                 bool reject_ambiguous, bool reject_saturated, int first_row, int last_row,
                 bool peaks_per_row) {
  triangulation::PeakDetectionOptions o;
  o.estimator = triangulation::ParsePeakEstimator(estimator);
  o.min_height = min_height;
  o.cog_threshold_fraction = cog_threshold_fraction;
  o.ambiguity_ratio = ambiguity_ratio;
  o.saturation_level = saturation_level;
  o.reject_ambiguous = reject_ambiguous;
  o.reject_saturated = reject_saturated;
  o.first_row = first_row;
  o.last_row = last_row;
  o.peaks_per_row = peaks_per_row;
  o.Check("detect_peaks");
  if (image.ndim() != 2 || image.shape(0) == 0 || image.shape(1) == 0) {
    ThrowInput("image: expected a non-empty (H, W) gray image");
  }
  const bool is8 = image.dtype().is(py::dtype::of<std::uint8_t>());
  if (!is8 && !image.dtype().is(py::dtype::of<std::uint16_t>())) {
    throw py::type_error("image: expected dtype uint8 or uint16, got " +
                         std::string(py::str(image.dtype())));
  }
  if (is8) {
    const auto view = View<std::uint8_t>(image);
    py::gil_scoped_release release;
    return std::make_shared<PeakDetectionResult>(triangulation::DetectPeaks(view, o));
  }
  const auto view = View<std::uint16_t>(image);
  py::gil_scoped_release release;
  return std::make_shared<PeakDetectionResult>(triangulation::DetectPeaks(view, o));
}

// A read-only (W,) view of one per-column array of the result's profile, kept alive by it.
auto Column(std::vector<float> triangulation::Profile::*values) {
  return [values](const py::object& self) {
    const std::vector<float>& v = self.cast<const PeakDetectionResult&>().profile.*values;
    return ReadOnlyView(v.data(), v.size(), 1, self);
  };
}

}  // namespace

void BindPeaks(py::module_& m) {
  py::class_<PeakDetectionResult, ResultPtr>(m, "PeakDetectionResult",
                                             LC_DOC(triangulation_PeakDetectionResult))
      .def_property_readonly("row_px", Column(&triangulation::Profile::row_px),
                             "(W,) float32 subpixel peak row per column (pixel centres at "
                             "integers); NaN = none.")
      .def_property_readonly("intensity", Column(&triangulation::Profile::intensity),
                             "(W,) peak height above the background / full scale, 0..1.")
      .def_property_readonly("width_px", Column(&triangulation::Profile::width_px),
                             "(W,) full width at half height, px.")
      .def_property_readonly(
          "status",
          [](const py::object& self) {
            const auto& s = self.cast<const PeakDetectionResult&>().status;
            return ReadOnlyView(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), 1, self);
          },
          "(W,) uint8: 0 no peak, 1 valid, 2 saturated, 3 ambiguous (a second peak).")
      .def_property_readonly(
          "background",
          [](const py::object& self) {
            const auto& b = self.cast<const PeakDetectionResult&>().background;
            return ReadOnlyView(b.data(), b.size(), 1, self);
          },
          "(W,) background level per column, gray levels.")
      .def_readonly("valid", &PeakDetectionResult::valid,
                    LC_DOC(triangulation_PeakDetectionResult_valid))
      .def_readonly("saturated", &PeakDetectionResult::saturated,
                    LC_DOC(triangulation_PeakDetectionResult_saturated))
      .def_readonly("ambiguous", &PeakDetectionResult::ambiguous,
                    LC_DOC(triangulation_PeakDetectionResult_ambiguous))
      .def_readonly("no_peak", &PeakDetectionResult::no_peak,
                    LC_DOC(triangulation_PeakDetectionResult_no_peak))
      .def("summary", &PeakDetectionResult::Summary,
           LC_DOC(triangulation_PeakDetectionResult_Summary))
      .def("__repr__", [](const PeakDetectionResult& r) {
        return "<lasercell.PeakDetectionResult " + r.Summary() + ">";
      });
  m.def("detect_peaks", &Detect, py::arg("image"), py::arg("estimator") = "gaussian",
        py::arg("min_height") = 20.0, py::arg("cog_threshold_fraction") = 0.5,
        py::arg("ambiguity_ratio") = 0.5, py::arg("saturation_level") = 0.0,
        py::arg("reject_ambiguous") = false, py::arg("reject_saturated") = false,
        py::arg("first_row") = -1, py::arg("last_row") = -1, py::arg("peaks_per_row") = false,
        LC_DOC(triangulation_DetectPeaks) R"doc(

In Python: image: (H, W) uint8 or uint16 (thresholds in its own gray levels), read in place.
estimator: 'gaussian' (three-point fit), 'cog' (threshold-subtracted centre of gravity) or
'blais-rioux' (zero crossing of the 4th-order FIR derivative). Saturated and ambiguous columns
are reported in status, dropped only when reject_saturated / reject_ambiguous. first_row,
last_row: the rows searched (-1 = all). peaks_per_row: the stripe runs along the columns.
OptionError names a bad option; TypeError/InputError a bad image.)doc");
}

}  // namespace lasercell::python
