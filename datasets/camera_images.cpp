#include "datasets/camera_images.hpp"

extern "C" {
#include <mrcal/mrcal.h>
}

#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "datasets/rng.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// Cell index of a target-frame coordinate along one axis: -2 off the plate, -1 border before the
// pattern, 0..n-1 squares, n border after, n + 1 off the plate.
int AxisCell(double v, int n, double square, double border) {
  if (v < -border) return -2;
  if (v < 0) return -1;
  if (v < n * square) return std::min(n - 1, static_cast<int>(std::floor(v / square)));
  if (v <= n * square + border) return n;
  return n + 1;
}

double CellAlbedo(int cx, int cy, const ChessboardTarget& b, double background) {
  const int nx = b.SquaresX(), ny = b.SquaresY();
  if (cx == -2 || cy == -2 || cx == nx + 1 || cy == ny + 1) return background;
  if (cx == -1 || cy == -1 || cx == nx || cy == ny) return b.light_albedo;
  return ((cx + cy) % 2 == 0) ? b.dark_albedo : b.light_albedo;
}

// Separable Gaussian blur with replicated borders.
void GaussianBlur(std::vector<float>& img, int w, int h, double sigma) {
  if (sigma <= 0) return;
  const int r = std::max(1, static_cast<int>(std::ceil(3.5 * sigma)));
  std::vector<float> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i)
    sum += k[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (float& v : k) v = static_cast<float>(v / sum);
  std::vector<float> tmp(img.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float acc = 0;
      for (int i = -r; i <= r; ++i) acc += k[i + r] * img[y * w + std::clamp(x + i, 0, w - 1)];
      tmp[y * w + x] = acc;
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float acc = 0;
      for (int i = -r; i <= r; ++i) acc += k[i + r] * tmp[std::clamp(y + i, 0, h - 1) * w + x];
      img[y * w + x] = acc;
    }
  }
}

Image8 Quantize(const std::vector<float>& img, int w, int h, double noise_sigma,
                std::uint64_t seed) {
  Image8 out;  // gray
  out.width = w;
  out.height = h;
  out.pixels.resize(img.size());
  Rng rng(seed);
  for (std::size_t i = 0; i < img.size(); ++i) {
    const double v = img[i] + (noise_sigma > 0 ? noise_sigma * rng.Normal() : 0.0);
    out.pixels[i] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  }
  return out;
}

// Integral of the two-half-Gaussian profile of peak 1 (StripeShape) from -inf to t, t relative
// to the mode: s_lo sqrt(2 pi) Phi(t / s_lo) below the mode, plus s_hi sqrt(2 pi) (Phi(t / s_hi)
// - 1/2) above it.
double HalfGaussiansIntegral(double t, double s_lo, double s_hi) {
  constexpr double kSqrtHalfPi = 1.2533141373155003;  // sqrt(pi / 2)
  if (t < 0) return kSqrtHalfPi * s_lo * std::erfc(-t / (std::numbers::sqrt2 * s_lo));
  return kSqrtHalfPi * (s_lo + s_hi * std::erf(t / (std::numbers::sqrt2 * s_hi)));
}

// Multiplicative log-normal speckle over n consecutive rows of one column (StripeShape): a
// unit-variance Gaussian process g (white normals filtered by a Gaussian kernel of sigma grain /
// sqrt(2), weights normalized to unit sum of squares, so Var g = 1 exactly and its
// autocorrelation is exp(-d^2 / (2 grain^2))), mapped to exp(sigma_l g - sigma_l^2 / 2) with
// sigma_l^2 = ln(1 + C^2): mean 1 and std C (log-normal moments; Goodman, "Speckle Phenomena in
// Optics", 2007, for the contrast of integrated speckle).
std::vector<double> SpeckleField(int n, const StripeShape& shape, std::uint64_t seed) {
  const double kernel_sigma = shape.speckle_grain_px / std::numbers::sqrt2;
  const int r = std::max(1, static_cast<int>(std::ceil(4 * kernel_sigma)));
  std::vector<double> kernel(2 * r + 1);
  double sum2 = 0;
  for (int i = -r; i <= r; ++i) {
    kernel[i + r] = std::exp(-0.5 * i * i / (kernel_sigma * kernel_sigma));
    sum2 += kernel[i + r] * kernel[i + r];
  }
  for (double& k : kernel) k /= std::sqrt(sum2);
  Rng rng(seed);
  std::vector<double> white(static_cast<std::size_t>(n + 2 * r));
  for (double& v : white) v = rng.Normal();
  const double sigma_l2 = std::log1p(shape.speckle_contrast * shape.speckle_contrast);
  const double sigma_l = std::sqrt(sigma_l2);
  std::vector<double> field(static_cast<std::size_t>(n));
  for (int y = 0; y < n; ++y) {
    double g = 0;
    for (int i = 0; i <= 2 * r; ++i) g += kernel[i] * white[y + i];
    field[y] = std::exp(sigma_l * g - 0.5 * sigma_l2);
  }
  return field;
}

// Adds one column's stripe (gray levels above the ambient) of the exposure's row, FWHM and
// intensity, shaped by `shape`; speckle drawn from `speckle_seed`. With StripeShape{} every
// operation reduces to the point-sampled Gaussian exactly (factors of 1.0, offsets of 0.0).
void AddStripe(std::vector<float>& img, int w, int h, int x, double row, double width_px,
               double intensity, const StripeShape& shape, std::uint64_t speckle_seed) {
  const double sigma = width_px / 2.3548200450309493;  // FWHM -> sigma
  const double peak = 255.0 * intensity * shape.peak_gain;
  const double s_lo = (1 - shape.asymmetry) * sigma;  // rows above the mode
  const double s_hi = (1 + shape.asymmetry) * sigma;  // rows below it
  const double reach = 5 * std::max(s_lo, s_hi) + (shape.integrate_pixel_area ? 0.5 : 0.0);
  const int y0 = std::max(0, static_cast<int>(std::floor(row - reach)));
  const int y1 = std::min(h - 1, static_cast<int>(std::ceil(row + reach)));
  if (y1 < y0) return;
  std::vector<double> speckle;
  if (shape.speckle_contrast > 0) speckle = SpeckleField(y1 - y0 + 1, shape, speckle_seed);
  for (int y = y0; y <= y1; ++y) {
    double value;
    if (shape.integrate_pixel_area) {
      // Mean over the pixel's extent [y - 1/2, y + 1/2] (fill factor 1).
      value = peak * (HalfGaussiansIntegral(y + 0.5 - row, s_lo, s_hi) -
                      HalfGaussiansIntegral(y - 0.5 - row, s_lo, s_hi));
    } else {
      const double d = (y - row) / (y < row ? s_lo : s_hi);
      value = peak * std::exp(-0.5 * d * d);
    }
    if (!speckle.empty()) value *= speckle[y - y0];
    img[static_cast<std::size_t>(y) * w + x] += static_cast<float>(value);
  }
}

// Speckle streams of StreamSeed(seed, .): one per column and peak (stripe, ghost), well away
// from the small stream ids other renderers use.
constexpr std::uint64_t kSpeckleStream = 1ull << 40;

// The target frame from BoardSpec's chessboard frame in units of one square: BoardSpec's origin,
// the first inner corner, is one square in from the pattern's outer corner along x and y.
Eigen::Isometry3d TargetFromBoardInSquares() {
  Eigen::Isometry3d target_from_board = Eigen::Isometry3d::Identity();
  target_from_board.translation() = Eigen::Vector3d(1.0, 1.0, 0.0);
  return target_from_board;
}

}  // namespace

Eigen::Isometry3d ChessboardTarget::TargetFromBoard() const {
  Eigen::Isometry3d target_from_board = TargetFromBoardInSquares();
  target_from_board.translation() *= board.square_mm;
  return target_from_board;
}

std::vector<Eigen::Vector3d> ChessboardTarget::CornersInTarget() const {
  // TargetFromBoard() * board.Corners(), evaluated in squares (small integers, exact) and then
  // scaled, so that corner (c, r) is the correctly rounded (c + 1) * square_mm: adding square_mm
  // to the rounded c * square_mm can differ in the last bit when the size is not a binary
  // fraction (e.g. 25.4 mm).
  calib::BoardSpec in_squares = board;
  in_squares.square_mm = 1.0;
  const Eigen::Isometry3d target_from_board_in_squares = TargetFromBoardInSquares();
  std::vector<Eigen::Vector3d> corners = in_squares.Corners();
  for (Eigen::Vector3d& p : corners) p = board.square_mm * (target_from_board_in_squares * p);
  return corners;
}

void ChessboardTarget::Check(const std::string& what) const {
  if (board.type != calib::BoardType::kChessboard) {
    throw OptionError(what + ".board.type must be chessboard (the renderer draws no markers)");
  }
  const int nx = SquaresX(), ny = SquaresY();
  if (nx < 3 || ny < 3 || nx > 100 || ny > 100) {
    throw OptionError(what + ".squares must be in [3, 100] per axis (got " + std::to_string(nx) +
                      " x " + std::to_string(ny) + ")");
  }
  if (!(board.square_mm > 0) || !(border_mm >= 0)) {
    throw OptionError(what + ".square_mm must be positive and border_mm >= 0");
  }
  if (!(dark_albedo >= 0 && dark_albedo <= 1 && light_albedo >= 0 && light_albedo <= 1)) {
    throw OptionError(what + ".dark_albedo/light_albedo must be in [0, 1]");
  }
}

void ImageRenderOptions::Check(const std::string& what) const {
  if (!(exposure > 0)) throw OptionError(what + ".exposure must be positive");
  if (!(ambient >= 0 && ambient < 255)) throw OptionError(what + ".ambient must be in [0, 255)");
  if (!(background_albedo >= 0 && background_albedo <= 1)) {
    throw OptionError(what + ".background_albedo must be in [0, 1]");
  }
  if (!(blur_sigma_px >= 0 && blur_sigma_px <= 20)) {
    throw OptionError(what + ".blur_sigma_px must be in [0, 20] (got " +
                      std::to_string(blur_sigma_px) + ")");
  }
  if (!(noise_sigma >= 0 && noise_sigma <= 100)) {
    throw OptionError(what + ".noise_sigma must be in [0, 100] (got " +
                      std::to_string(noise_sigma) + ")");
  }
  if (edge_samples < 1 || edge_samples > 64) {
    throw OptionError(what + ".edge_samples must be in [1, 64]");
  }
}

void StripeShape::Check(const std::string& what) const {
  if (!(asymmetry >= -0.9 && asymmetry <= 0.9)) {
    throw OptionError(what + ".asymmetry must be in [-0.9, 0.9] (got " + std::to_string(asymmetry) +
                      ")");
  }
  if (!(speckle_contrast >= 0 && speckle_contrast <= 1)) {
    throw OptionError(what + ".speckle_contrast must be in [0, 1] (got " +
                      std::to_string(speckle_contrast) + ")");
  }
  if (!(speckle_grain_px >= 0.5 && speckle_grain_px <= 50)) {
    throw OptionError(what + ".speckle_grain_px must be in [0.5, 50] (got " +
                      std::to_string(speckle_grain_px) + ")");
  }
  if (!(peak_gain > 0 && peak_gain <= 100)) {
    throw OptionError(what + ".peak_gain must be in (0, 100] (got " + std::to_string(peak_gain) +
                      ")");
  }
}

std::vector<std::string> StripeShapePresetNames() {
  return {"sampled-gaussian", "pixel-area", "asymmetric", "speckle", "saturated"};
}

StripeShape StripeShapePreset(const std::string& name) {
  StripeShape shape;
  if (name == "sampled-gaussian") return shape;
  shape.integrate_pixel_area = true;
  if (name == "pixel-area") return shape;
  if (name == "asymmetric") {
    shape.asymmetry = 0.3;  // half-Gaussians of 0.7 s and 1.3 s
  } else if (name == "speckle") {
    shape.speckle_contrast = 0.25;
    shape.speckle_grain_px = 1.5;
  } else if (name == "saturated") {
    shape.peak_gain = 4.0;
  } else {
    std::string known;
    for (const std::string& n : StripeShapePresetNames()) known += (known.empty() ? "" : ", ") + n;
    throw OptionError("stripe shape '" + name + "' is not one of " + known);
  }
  return shape;
}

ImageRenderer::ImageRenderer(const calib::CameraModel& camera) : camera_(camera) {
  const int w = camera.width_px();
  const int h = camera.height_px();
  std::vector<mrcal_point2_t> q;
  q.reserve(static_cast<std::size_t>(w + 1) * (h + 1));
  for (int y = 0; y <= h; ++y) {
    for (int x = 0; x <= w; ++x) q.push_back({{x - 0.5, y - 0.5}});
  }
  std::vector<mrcal_point3_t> v(q.size());
  if (!mrcal_unproject(v.data(), q.data(), static_cast<int>(q.size()), &camera.mrcal_lensmodel(),
                       camera.intrinsics().data())) {
    throw InternalError("mrcal_unproject failed for the pixel-corner grid");
  }
  corner_rays_.resize(q.size());
  for (std::size_t i = 0; i < q.size(); ++i) {
    corner_rays_[i] = Eigen::Vector2d(v[i].x / v[i].z, v[i].y / v[i].z);
  }
}

Image8 ImageRenderer::RenderChessboard(const ChessboardTarget& target,
                                       const Eigen::Isometry3d& camera_from_board,
                                       const ImageRenderOptions& options,
                                       std::uint64_t seed) const {
  target.Check();
  options.Check();
  const int w = camera_.width_px();
  const int h = camera_.height_px();
  const int nx = target.SquaresX(), ny = target.SquaresY();
  const double s = target.board.square_mm;
  // (x, y, 1) ~ [r1 r2 t] (bx, by, 1): the board plane's homography and its inverse.
  Eigen::Matrix3d hom;
  hom << camera_from_board.linear().col(0), camera_from_board.linear().col(1),
      camera_from_board.translation();
  const Eigen::Matrix3d inv = hom.inverse();
  const auto to_board = [&](const Eigen::Vector2d& n, Eigen::Vector2d* b) {
    const Eigen::Vector3d p = inv * Eigen::Vector3d(n.x(), n.y(), 1.0);
    if (!(p.z() > 0)) return false;  // the ray meets the plane behind the camera
    *b = p.head<2>() / p.z();
    return true;
  };
  const auto albedo_at = [&](const Eigen::Vector2d& n) {
    Eigen::Vector2d b;
    if (!to_board(n, &b)) return options.background_albedo;
    return CellAlbedo(AxisCell(b.x(), nx, s, target.border_mm),
                      AxisCell(b.y(), ny, s, target.border_mm), target, options.background_albedo);
  };
  std::vector<float> img(static_cast<std::size_t>(w) * h);
  const int ns = options.edge_samples;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector2d& c00 = corner_rays_[static_cast<std::size_t>(y) * (w + 1) + x];
      const Eigen::Vector2d& c10 = corner_rays_[static_cast<std::size_t>(y) * (w + 1) + x + 1];
      const Eigen::Vector2d& c01 = corner_rays_[static_cast<std::size_t>(y + 1) * (w + 1) + x];
      const Eigen::Vector2d& c11 = corner_rays_[static_cast<std::size_t>(y + 1) * (w + 1) + x + 1];
      // Uniform pixel: all four corners on the plate side of the camera and in one cell.
      double albedo = -1;
      Eigen::Vector2d b[4];
      if (to_board(c00, &b[0]) && to_board(c10, &b[1]) && to_board(c01, &b[2]) &&
          to_board(c11, &b[3])) {
        int cx[4], cy[4];
        for (int k = 0; k < 4; ++k) {
          cx[k] = AxisCell(b[k].x(), nx, s, target.border_mm);
          cy[k] = AxisCell(b[k].y(), ny, s, target.border_mm);
        }
        if (cx[0] == cx[1] && cx[0] == cx[2] && cx[0] == cx[3] && cy[0] == cy[1] &&
            cy[0] == cy[2] && cy[0] == cy[3]) {
          albedo = CellAlbedo(cx[0], cy[0], target, options.background_albedo);
        }
      }
      if (albedo < 0) {
        // An edge crosses the pixel: box-filter over ns x ns sub-samples on an n-rooks
        // ("multi-jittered", Chiu, Shirley, Wang 1994, without the jitter) pattern: sample (i, j)
        // at ((i + (j + 0.5) / ns) / ns, (j + (i + 0.5) / ns) / ns), so the ns^2 samples take
        // ns^2 distinct x and ns^2 distinct y offsets. An axis-aligned edge's covered area is
        // then resolved to 1 / ns^2 of a pixel instead of the 1 / ns of a regular grid (0.002 vs
        // 0.031 px position error at ns = 16; EdgePixelsHoldTheExactCoveredArea).
        double sum = 0;
        for (int j = 0; j < ns; ++j) {
          for (int i = 0; i < ns; ++i) {
            const double fx = (i + (j + 0.5) / ns) / ns;
            const double fy = (j + (i + 0.5) / ns) / ns;
            const Eigen::Vector2d left = (1 - fy) * c00 + fy * c01;
            const Eigen::Vector2d right = (1 - fy) * c10 + fy * c11;
            sum += albedo_at((1 - fx) * left + fx * right);
          }
        }
        albedo = sum / (ns * ns);
      }
      double gain = 1.0;
      if (options.vignetting) {
        const Eigen::Vector2d n = 0.25 * (c00 + c10 + c01 + c11);
        const double cos2 = 1.0 / (1.0 + n.squaredNorm());
        gain = cos2 * cos2;
      }
      img[static_cast<std::size_t>(y) * w + x] =
          static_cast<float>(options.ambient + options.exposure * albedo * gain);
    }
  }
  GaussianBlur(img, w, h, options.blur_sigma_px);
  return Quantize(img, w, h, options.noise_sigma, seed);
}

Image8 ImageRenderer::RenderLaserLine(const ExposureTruth& exposure,
                                      const ImageRenderOptions& options, std::uint64_t seed) const {
  return RenderLaserLine(exposure, options, StripeShape{}, seed);
}

Image8 ImageRenderer::RenderLaserLine(const ExposureTruth& exposure,
                                      const ImageRenderOptions& options, const StripeShape& shape,
                                      std::uint64_t seed) const {
  options.Check();
  shape.Check();
  const int w = camera_.width_px();
  const int h = camera_.height_px();
  LASERCELL_CHECK(static_cast<int>(exposure.row_px.size()) == w, "exposure width matches camera");
  std::vector<float> img(static_cast<std::size_t>(w) * h, static_cast<float>(options.ambient));
  for (int x = 0; x < w; ++x) {
    const std::uint64_t stream = kSpeckleStream + 2 * static_cast<std::uint64_t>(x);
    if (!std::isnan(exposure.row_px[x])) {
      AddStripe(img, w, h, x, exposure.row_px[x], exposure.width_px[x], exposure.intensity[x],
                shape, StreamSeed(seed, stream));
    }
    // Specular ghosts (laser_renderer.hpp), when the exposure has them: a second, weaker peak.
    if (!exposure.reflection_row_px.empty() && !std::isnan(exposure.reflection_row_px[x])) {
      AddStripe(img, w, h, x, exposure.reflection_row_px[x], 2.0, exposure.reflection_intensity[x],
                shape, StreamSeed(seed, stream + 1));
    }
  }
  return Quantize(img, w, h, options.noise_sigma, seed);
}

std::vector<Eigen::Isometry3d> DrawChessboardPoses(const ChessboardTarget& target,
                                                   const calib::CameraModel& camera, int count,
                                                   std::uint64_t seed) {
  target.Check();
  Rng rng(seed);
  const int w = camera.width_px();
  const int h = camera.height_px();
  const double sx = target.SquaresX() * target.board.square_mm;
  const double sy = target.SquaresY() * target.board.square_mm;
  const Eigen::Vector3d center(sx / 2, sy / 2, 0);
  const std::vector<Eigen::Vector3d> corners = target.CornersInTarget();
  const double bx = target.border_mm;
  const std::array<Eigen::Vector3d, 4> plate = {
      Eigen::Vector3d(-bx, -bx, 0), Eigen::Vector3d(sx + bx, -bx, 0),
      Eigen::Vector3d(sx + bx, sy + bx, 0), Eigen::Vector3d(-bx, sy + bx, 0)};
  std::vector<Eigen::Isometry3d> poses;
  for (int attempt = 0; static_cast<int>(poses.size()) < count; ++attempt) {
    if (attempt > 1000 * count) {
      throw OptionError(
          "chessboard: no board pose of this size fits the camera's view; use a "
          "smaller board (squares, square_mm)");
    }
    const double distance = rng.Uniform(550, 850);
    const double tilt = rng.Uniform(5, 40) * kDegToRad;
    const double tilt_axis = rng.Uniform(0, 2 * std::numbers::pi);
    const double yaw = rng.Uniform(-std::numbers::pi, std::numbers::pi);
    const Eigen::Vector2d pixel{rng.Uniform(0.2, 0.8) * w, rng.Uniform(0.2, 0.8) * h};
    // Board +z towards the camera (RotX(pi)), then yaw about the board normal, then tilt.
    const Eigen::Matrix3d r =
        (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(tilt_axis), std::sin(tilt_axis), 0)) *
         Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()) *
         Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()))
            .toRotationMatrix();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = r;
    pose.translation() = distance * camera.Unproject(pixel) - r * center;
    bool ok = true;
    for (const Eigen::Vector3d& p : plate) {
      const auto q = ProjectInView(camera, pose * p);
      ok = ok && q && camera.InImage(*q);
    }
    for (const Eigen::Vector3d& p : corners) {
      const auto q = ProjectInView(camera, pose * p);
      ok = ok && q && q->x() >= 25 && q->y() >= 25 && q->x() <= w - 26 && q->y() <= h - 26;
    }
    if (ok) poses.push_back(pose);
  }
  return poses;
}

std::string EncodePng(const Image8& image) {
  const cv::Mat mat(image.height, image.width, CV_8UC(image.channels),
                    const_cast<std::uint8_t*>(image.pixels.data()));
  std::vector<unsigned char> buffer;
  if (!cv::imencode(".png", mat, buffer, {cv::IMWRITE_PNG_COMPRESSION, 6})) {
    throw InternalError("OpenCV could not encode a PNG");
  }
  return std::string(buffer.begin(), buffer.end());
}

}  // namespace lasercell::datasets
