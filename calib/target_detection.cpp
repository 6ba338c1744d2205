#include "calib/target_detection.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <opencv2/aruco/charuco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace lasercell::calib {
namespace {

cv::aruco::PREDEFINED_DICTIONARY_NAME DictionaryByName(const std::string& name) {
  static const std::pair<const char*, cv::aruco::PREDEFINED_DICTIONARY_NAME> kNames[] = {
      {"DICT_4X4_50", cv::aruco::DICT_4X4_50},
      {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
      {"DICT_4X4_250", cv::aruco::DICT_4X4_250},
      {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
      {"DICT_5X5_50", cv::aruco::DICT_5X5_50},
      {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
      {"DICT_5X5_250", cv::aruco::DICT_5X5_250},
      {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
      {"DICT_6X6_50", cv::aruco::DICT_6X6_50},
      {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
      {"DICT_6X6_250", cv::aruco::DICT_6X6_250},
      {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
      {"DICT_7X7_50", cv::aruco::DICT_7X7_50},
      {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
      {"DICT_7X7_250", cv::aruco::DICT_7X7_250},
      {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
      {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
      {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5},
      {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9},
      {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10},
      {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11},
  };
  for (const auto& [n, v] : kNames) {
    if (name == n) return v;
  }
  throw OptionError("BoardSpec.dictionary '" + name +
                    "' is not an OpenCV ArUco dictionary (DICT_4X4_50 ... DICT_7X7_1000, "
                    "DICT_ARUCO_ORIGINAL, DICT_APRILTAG_16h5/25h9/36h10/36h11)");
}

// Smallest distance between grid neighbours (5th percentile, robust to one bad corner), px.
double SquareSizePx(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids, int nx) {
  std::vector<double> d;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    for (std::size_t j = 0; j < ids.size(); ++j) {
      const bool right = ids[j] == ids[i] + 1 && ids[i] % nx != nx - 1;
      const bool below = ids[j] == ids[i] + nx;
      if (right || below) d.push_back(cv::norm(corners[i] - corners[j]));
    }
  }
  if (d.empty()) return 0;
  std::sort(d.begin(), d.end());
  return d[d.size() / 20];
}

// Where corner i should be, from a homography (grid -> image) through the trusted corners within
// two grid steps of it: a square's neighbourhood is close to planar-projective even under lens
// distortion. False when fewer than 6 trusted neighbours surround it.
bool PredictFromNeighbours(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
                           int nx, const std::vector<char>& trusted, std::size_t i,
                           cv::Point2f* predicted) {
  const int ci = ids[i] % nx, ri = ids[i] / nx;
  std::vector<cv::Point2f> grid, image;
  for (std::size_t j = 0; j < ids.size(); ++j) {
    const int cj = ids[j] % nx, rj = ids[j] / nx;
    if (j == i || !trusted[j] || std::abs(cj - ci) > 2 || std::abs(rj - ri) > 2) continue;
    grid.emplace_back(static_cast<float>(cj), static_cast<float>(rj));
    image.push_back(corners[j]);
  }
  if (grid.size() < 6) return false;
  const cv::Mat h = cv::findHomography(grid, image, 0);
  if (h.empty()) return false;
  std::vector<cv::Point2f> out;
  cv::perspectiveTransform(
      std::vector<cv::Point2f>{{static_cast<float>(ci), static_cast<float>(ri)}}, out, h);
  *predicted = out[0];
  return std::isfinite(out[0].x) && std::isfinite(out[0].y);
}

void Refine(const cv::Mat& gray, std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
            int nx, const DetectionOptions& options, TargetDetection& out) {
  out.square_px = SquareSizePx(corners, ids, nx);
  if (!options.refine || corners.empty()) return;
  const int half =
      std::clamp(static_cast<int>(std::floor(options.refine_window_fraction * out.square_px)),
                 options.min_refine_half_window_px, options.max_refine_half_window_px);
  const std::vector<cv::Point2f> before = corners;
  const cv::TermCriteria stop(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4);
  cv::cornerSubPix(gray, corners, cv::Size(half, half), cv::Size(-1, -1), stop);
  out.refine_half_window_px = half;
  // A corner that moved farther than the limit either ran onto another edge (the full window
  // reached the board's rim) or started from a detector estimate that was itself off (SB's
  // corners on strongly foreshortened squares, seen 3 px off). Candidates: the full window,
  // halved windows, the detector's estimate; the one nearest the neighbours' homography wins.
  // Without enough neighbours: the first smaller window that stays within the limit, else the
  // detector's estimate.
  const double limit = options.refine_shift_limit_px * options.search_downscale;
  std::vector<char> trusted(corners.size());
  for (std::size_t i = 0; i < corners.size(); ++i)
    trusted[i] = cv::norm(corners[i] - before[i]) <= limit ? 1 : 0;
  const std::vector<cv::Point2f> refined = corners;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (trusted[i]) continue;
    ++out.rerefined_corners;
    out.rerefined.push_back(static_cast<int>(i));
    std::vector<cv::Point2f> candidates = {refined[i]};
    for (int h = half / 2; h >= options.min_refine_half_window_px; h /= 2) {
      std::vector<cv::Point2f> one = {before[i]};
      cv::cornerSubPix(gray, one, cv::Size(h, h), cv::Size(-1, -1), stop);
      candidates.push_back(one[0]);
    }
    cv::Point2f predicted;
    corners[i] = before[i];
    if (PredictFromNeighbours(refined, ids, nx, trusted, i, &predicted)) {
      double best = cv::norm(before[i] - predicted);
      for (const cv::Point2f& c : candidates) {
        if (cv::norm(c - predicted) < best) {
          best = cv::norm(c - predicted);
          corners[i] = c;
        }
      }
    } else {
      for (std::size_t k = 1; k < candidates.size(); ++k) {
        if (cv::norm(candidates[k] - before[i]) <= limit) {
          corners[i] = candidates[k];
          break;
        }
      }
    }
    if (corners[i] == before[i]) ++out.unrefined_corners;
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    out.max_refine_shift_px =
        std::max(out.max_refine_shift_px, static_cast<double>(cv::norm(corners[i] - before[i])));
  }
}

void Store(const std::vector<cv::Point2f>& corners, const std::vector<int>& ids,
           TargetDetection& out) {
  out.corners_px.clear();
  for (const cv::Point2f& c : corners) out.corners_px.emplace_back(c.x, c.y);
  out.corner_ids = ids;
}

// The image the board is searched in: `gray` itself, or shrunk by options.search_downscale.
cv::Mat SearchImage(const cv::Mat& gray, const DetectionOptions& options) {
  const int s = options.search_downscale;
  if (s == 1) return gray;
  cv::Mat small;
  cv::resize(gray, small, cv::Size(gray.cols / s, gray.rows / s), 0, 0, cv::INTER_AREA);
  return small;
}

// Search-image pixels back to full resolution: an area average of s x s pixels puts the centre
// of small pixel x at full-resolution s x + (s - 1) / 2 (pixel centres at integers).
void ToFullResolution(std::vector<cv::Point2f>& corners, const DetectionOptions& options) {
  const float s = static_cast<float>(options.search_downscale);
  const float shift = 0.5f * (s - 1.f);
  for (cv::Point2f& c : corners) c = cv::Point2f(s * c.x + shift, s * c.y + shift);
}

// The inner-corner grid of any chessboard of at least 3x3 inner corners in the image (SB with
// CALIB_CB_LARGER grows the grid to the whole board and reports its size through `meta`), or
// 0x0 when there is none. Only words the failure message: a partial grid (a board cut off, or
// one that SB grows only partly, e.g. across a laser stripe) says nothing about whether another
// detector finds the board, so it never decides which detectors run.
cv::Size VisibleChessboard(const cv::Mat& search) {
  std::vector<cv::Point2f> any;
  cv::Mat meta;
  try {
    if (cv::findChessboardCornersSB(search, cv::Size(3, 3), any,
                                    cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_LARGER, meta) &&
        !meta.empty()) {
      return cv::Size(meta.cols, meta.rows);
    }
  } catch (const cv::Exception&) {
  }
  return cv::Size(0, 0);
}

// One chessboard search of the cascade.
struct ChessboardSearch {
  const char* name;  // TargetDetection::detector
  bool sb;           // findChessboardCornersSB, else the classic findChessboardCorners
  int flags;
};

// The cascade (documented in target_detection.hpp), tried in order on the search image until one
// search returns the whole board. Cheap and most often successful first: SB + NORMALIZE finds
// most boards in one pass; ACCURACY (SB on a 2x upsampled image) recovers small or blurred
// squares; EXHAUSTIVE + ACCURACY tries harder on cluttered views; the classic quad detector with
// adaptive threshold survives some views SB splits. Every SB search normalises: without
// NORMALIZE, SB (plain, ACCURACY or EXHAUSTIVE) finds a 9x7 board in OpenCV's 9x6 samples
// left01-04 (the board's outer edge taken for one more row of corners), measured on OpenCV 4.6.
// Every search runs whatever earlier probes say: a failed image pays the whole cascade.
constexpr ChessboardSearch kChessboardCascade[] = {
    {"sb_normalize", true, cv::CALIB_CB_NORMALIZE_IMAGE},
    {"sb_normalize_accuracy", true, cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_ACCURACY},
    {"sb_normalize_exhaustive_accuracy", true,
     cv::CALIB_CB_NORMALIZE_IMAGE | cv::CALIB_CB_EXHAUSTIVE | cv::CALIB_CB_ACCURACY},
    {"classic_adaptive_normalize", false,
     cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE},
};

// Runs the cascade; the name of the search that found all pattern.area() corners, or nullptr.
// An OpenCV exception in one search counts as a miss of that search only.
const char* SearchChessboard(const cv::Mat& search, cv::Size pattern,
                             std::vector<cv::Point2f>& corners) {
  for (const ChessboardSearch& s : kChessboardCascade) {
    corners.clear();
    bool found = false;
    try {
      found = s.sb ? cv::findChessboardCornersSB(search, pattern, corners, s.flags)
                   : cv::findChessboardCorners(search, pattern, corners, s.flags);
    } catch (const cv::Exception&) {
      found = false;
    }
    if (found && static_cast<int>(corners.size()) == pattern.area()) return s.name;
  }
  corners.clear();
  return nullptr;
}

// The detectors may return a mirrored order (rows or columns reversed), i.e. the board seen from
// behind. Reverses the rows of a left-handed grid so every view has the board's z pointing away
// from the camera (board x along increasing ids, y down the rows).
void MakeRightHanded(std::vector<cv::Point2f>& corners, const BoardSpec& board) {
  const cv::Point2f dx = corners[1] - corners[0];
  const cv::Point2f dy = corners[board.cols] - corners[0];
  if (dx.x * dy.y - dx.y * dy.x >= 0) return;
  for (int r = 0; r < board.rows; ++r) {
    std::reverse(corners.begin() + r * board.cols, corners.begin() + (r + 1) * board.cols);
  }
}

// The failure: kNotFound, or kWrongBoardSize when (options.diagnose_board_size) the probe sees a
// grid of another size. Runs only after every search of the cascade failed.
void DiagnoseMissingChessboard(const cv::Mat& search, const BoardSpec& board,
                               const DetectionOptions& options, TargetDetection& out) {
  const std::string size = std::to_string(board.cols) + "x" + std::to_string(board.rows);
  out.status = DetectionStatus::kNotFound;
  out.message = "no " + size + " chessboard (inner corners) found by any of " +
                std::to_string(std::size(kChessboardCascade)) + " detectors";
  const cv::Size visible = options.diagnose_board_size ? VisibleChessboard(search) : cv::Size();
  if (visible.area() == 0) return;
  const int c = visible.width;
  const int r = visible.height;
  if ((c == board.cols && r == board.rows) || (c == board.rows && r == board.cols)) {
    out.message += " although a board of that size is visible (blurred, cut off or low contrast?)";
    return;
  }
  out.status = DetectionStatus::kWrongBoardSize;
  out.message = "no " + size + " chessboard found, but a " + std::to_string(c) + "x" +
                std::to_string(r) +
                " one (inner corners) is visible: wrong board size in the board spec? (a board "
                "partly outside the image or crossed by a laser line also looks smaller)";
}

void DetectChessboard(const cv::Mat& gray, const BoardSpec& board, const DetectionOptions& options,
                      TargetDetection& out) {
  const cv::Mat search = SearchImage(gray, options);
  std::vector<cv::Point2f> corners;
  const char* detector = SearchChessboard(search, cv::Size(board.cols, board.rows), corners);
  if (detector == nullptr) {
    DiagnoseMissingChessboard(search, board, options, out);
    return;
  }
  ToFullResolution(corners, options);
  MakeRightHanded(corners, board);
  std::vector<int> ids(corners.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<int>(i);
  Refine(gray, corners, ids, board.cols, options, out);
  Store(corners, ids, out);
  out.status = DetectionStatus::kFound;
  out.detector = detector;
  out.message = "found " + std::to_string(corners.size()) + " corners (square " +
                std::to_string(static_cast<int>(std::lround(out.square_px))) +
                " px, refinement half window " + std::to_string(out.refine_half_window_px) +
                " px, detector " + detector + ")";
  if (out.rerefined_corners > 0) {
    out.message += "; " + std::to_string(out.rerefined_corners) +
                   " corners ran off in the refinement window and were refined again with a "
                   "smaller one (" +
                   std::to_string(out.unrefined_corners) + " left unrefined)";
  }
}

void DetectCharuco(const cv::Mat& gray, const BoardSpec& board, const DetectionOptions& options,
                   TargetDetection& out) {
  const cv::Ptr<cv::aruco::Dictionary> dictionary =
      cv::aruco::getPredefinedDictionary(DictionaryByName(board.dictionary));
  const cv::Ptr<cv::aruco::CharucoBoard> charuco =
      cv::aruco::CharucoBoard::create(board.cols, board.rows, static_cast<float>(board.square_mm),
                                      static_cast<float>(board.marker_mm), dictionary);
  std::vector<std::vector<cv::Point2f>> marker_corners, rejected;
  std::vector<int> marker_ids;
  const cv::Ptr<cv::aruco::DetectorParameters> params = cv::aruco::DetectorParameters::create();
  const cv::Mat search = SearchImage(gray, options);
  cv::aruco::detectMarkers(search, dictionary, marker_corners, marker_ids, params, rejected);
  if (marker_ids.empty()) {
    out.status = DetectionStatus::kNotFound;
    out.message = "no ArUco marker of " + board.dictionary + " found";
    return;
  }
  std::vector<cv::Point2f> corners;
  std::vector<int> ids;
  if (cv::aruco::interpolateCornersCharuco(marker_corners, marker_ids, search, charuco, corners,
                                           ids) <= 0) {
    corners.clear();
    ids.clear();
  }
  ToFullResolution(corners, options);
  if (static_cast<int>(ids.size()) < options.min_charuco_corners) {
    out.status = ids.empty() ? DetectionStatus::kNotFound : DetectionStatus::kTooFewCorners;
    out.message = std::to_string(marker_ids.size()) + " markers but only " +
                  std::to_string(ids.size()) + " ChArUco corners (need " +
                  std::to_string(options.min_charuco_corners) +
                  "): wrong board size or marker dictionary?";
    return;
  }
  Refine(gray, corners, ids, board.CornersX(), options, out);
  Store(corners, ids, out);
  out.status = DetectionStatus::kFound;
  out.detector = "charuco";
  out.message = "found " + std::to_string(ids.size()) + " of " +
                std::to_string(board.NumCorners()) + " ChArUco corners (" +
                std::to_string(marker_ids.size()) + " markers)";
}

}  // namespace

const char* DetectionStatusName(DetectionStatus status) {
  switch (status) {
    case DetectionStatus::kFound:
      return "found";
    case DetectionStatus::kUnreadable:
      return "unreadable";
    case DetectionStatus::kNotFound:
      return "not_found";
    case DetectionStatus::kWrongBoardSize:
      return "wrong_board_size";
    case DetectionStatus::kTooFewCorners:
      return "too_few_corners";
  }
  return "unknown";
}

void DetectionOptions::Check() const {
  if (!(refine_window_fraction > 0 && refine_window_fraction < 0.5)) {
    throw OptionError("DetectionOptions.refine_window_fraction must be in (0, 0.5)");
  }
  if (!(refine_shift_limit_px > 0)) {
    throw OptionError("DetectionOptions.refine_shift_limit_px must be > 0");
  }
  if (min_refine_half_window_px < 1 || max_refine_half_window_px < min_refine_half_window_px) {
    throw OptionError(
        "DetectionOptions.min_refine_half_window_px must be >= 1 and <= max_refine_half_window_px");
  }
  if (min_charuco_corners < 4) {
    throw OptionError("DetectionOptions.min_charuco_corners must be >= 4");
  }
  if (search_downscale < 1 || search_downscale > 8) {
    throw OptionError("DetectionOptions.search_downscale must be in 1..8");
  }
  if (search_downscale > 1 && !refine) {
    throw OptionError(
        "DetectionOptions.search_downscale > 1 needs refine = true (corners found "
        "on the shrunk image are only good to about half the factor in px)");
  }
}

std::optional<Image8> DecodeGrayImage(const std::string& bytes) {
  if (bytes.empty()) return std::nullopt;
  cv::Mat raw(1, static_cast<int>(bytes.size()), CV_8UC1,
              const_cast<char*>(bytes.data()));  // imdecode only reads
  cv::Mat gray;
  try {
    gray = cv::imdecode(raw, cv::IMREAD_GRAYSCALE);
  } catch (const cv::Exception&) {
    return std::nullopt;
  }
  if (gray.empty() || gray.type() != CV_8UC1) return std::nullopt;
  Image8 image;  // one channel
  image.width = gray.cols;
  image.height = gray.rows;
  image.pixels.resize(static_cast<std::size_t>(gray.cols) * gray.rows);
  for (int r = 0; r < gray.rows; ++r) {
    std::copy(gray.ptr<std::uint8_t>(r), gray.ptr<std::uint8_t>(r) + gray.cols,
              image.pixels.begin() + static_cast<std::ptrdiff_t>(r) * gray.cols);
  }
  return image;
}

TargetDetection DetectTarget(const Image8& image, const BoardSpec& board,
                             const DetectionOptions& options) {
  board.Check();
  options.Check();
  TargetDetection out;
  out.width = image.width;
  out.height = image.height;
  if (image.channels != 1) {
    out.status = DetectionStatus::kUnreadable;
    out.message =
        "image has " + std::to_string(image.channels) + " channels; the detector takes gray";
    return out;
  }
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * image.height) {
    out.status = DetectionStatus::kUnreadable;
    out.message = "empty image or pixel count does not match its size";
    return out;
  }
  const cv::Mat gray(image.height, image.width, CV_8UC1,
                     const_cast<std::uint8_t*>(image.pixels.data()));  // read only
  try {
    if (board.type == BoardType::kChessboard) {
      DetectChessboard(gray, board, options, out);
    } else {
      DetectCharuco(gray, board, options, out);
    }
  } catch (const cv::Exception& e) {
    out = TargetDetection{};
    out.width = image.width;
    out.height = image.height;
    out.status = DetectionStatus::kNotFound;
    out.message = std::string("OpenCV failed on this image: ") + e.what();
  }
  return out;
}

TargetDetection DetectTargetInEncodedImage(const std::string& bytes, const BoardSpec& board,
                                           const DetectionOptions& options) {
  const std::optional<Image8> image = DecodeGrayImage(bytes);
  if (!image) {
    board.Check();
    TargetDetection out;
    out.status = DetectionStatus::kUnreadable;
    out.message = bytes.empty() ? "empty file, not an image"
                                : "not a readable image (JPEG, PNG, TIFF, BMP, ... expected)";
    return out;
  }
  return DetectTarget(*image, board, options);
}

}  // namespace lasercell::calib
