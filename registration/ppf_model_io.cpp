// Versioned binary encoding of PpfModel (little-endian, fixed-width fields):
//   "LCPPFMDL" | u32 version | u32 reserved | f64 diameter, max_pair, sampling, distance step,
//   angle step | i32 distance_bins, angle_bins, alpha_bins | f64[12] model_from_centered (3x4
//   row-major) | f64[3] principal variances | points | normals | refinement points | refinement
//   normals | keys | offsets | entries (u16 reference, u16 plane angle) | u64 FNV-1a checksum of
//   everything before it.
// Arrays are u64 count + raw elements. The dense key index is rebuilt on load.

#include <bit>
#include <cstring>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/raw_record.hpp"
#include "core/provenance.hpp"
#include "registration/ppf_model.hpp"

namespace lasercell::registration {

static_assert(std::endian::native == std::endian::little, "PPF model files are little-endian");
static_assert(sizeof(PpfPairEntry) == 4, "PpfPairEntry layout is part of the file format");

namespace {

constexpr char kMagic[8] = {'L', 'C', 'P', 'P', 'F', 'M', 'D', 'L'};
constexpr std::uint32_t kVersion = 1;

}  // namespace

// Friend of PpfModel: the only code that touches its fields from outside ppf_model.cpp.
class PpfModelCodec {
 public:
  static std::string Encode(const PpfModel& m) {
    io::RawWriter w;
    w.bytes().append(kMagic, sizeof(kMagic));
    w.Put(kVersion);
    w.Put(std::uint32_t{0});
    for (double v : {m.diameter_mm_, m.max_pair_distance_mm_, m.sampling_step_mm_,
                     m.distance_step_mm_, m.angle_step_rad_})
      w.Put(v);
    for (int v : {m.distance_bins_, m.angle_bins_, m.alpha_bins_})
      w.Put(static_cast<std::int32_t>(v));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) w.Put(m.model_from_centered_.matrix()(r, c));
    }
    for (int i = 0; i < 3; ++i) w.Put(m.principal_variances_(i));
    w.PutArray(m.points_);
    w.PutArray(m.normals_);
    w.PutArray(m.refinement_tree_.points());
    w.PutArray(m.refinement_normals_);
    w.PutArray(m.keys_);
    w.PutArray(m.offsets_);
    w.PutArray(m.entries_);
    w.Put(Fnv1a64(w.bytes()));
    return std::move(w.bytes());
  }

  static PpfModel Decode(std::string_view bytes, const std::string& name) {
    io::RawReader r(bytes, [&name](const std::string& problem) {
      throw InputError(name + ": not a valid lasercell PPF model (" + problem +
                       "); rebuild the model");
    });
    if (bytes.size() < sizeof(kMagic) || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
      r.Fail("bad magic; expected a file written by PpfModel::Save");
    }
    for (std::size_t i = 0; i < sizeof(kMagic); ++i) r.Get<char>("magic");
    const auto version = r.Get<std::uint32_t>("version");
    if (version != kVersion) {
      r.Fail("format version " + std::to_string(version) + ", this build reads version " +
             std::to_string(kVersion));
    }
    if (bytes.size() < sizeof(std::uint64_t)) r.Fail("truncated");
    std::uint64_t stored_sum;
    std::memcpy(&stored_sum, bytes.data() + bytes.size() - sizeof(stored_sum), sizeof(stored_sum));
    if (Fnv1a64(bytes.substr(0, bytes.size() - sizeof(stored_sum))) != stored_sum)
      r.Fail("checksum mismatch: the file is corrupt or truncated");
    r.Get<std::uint32_t>("reserved");
    PpfModel m;
    m.diameter_mm_ = r.Get<double>("diameter");
    m.max_pair_distance_mm_ = r.Get<double>("max_pair_distance");
    m.sampling_step_mm_ = r.Get<double>("sampling_step");
    m.distance_step_mm_ = r.Get<double>("distance_step");
    m.angle_step_rad_ = r.Get<double>("angle_step");
    m.distance_bins_ = r.Get<std::int32_t>("distance_bins");
    m.angle_bins_ = r.Get<std::int32_t>("angle_bins");
    m.alpha_bins_ = r.Get<std::int32_t>("alpha_bins");
    for (int row = 0; row < 3; ++row) {
      for (int c = 0; c < 4; ++c)
        m.model_from_centered_.matrix()(row, c) = r.Get<double>("model_from_centered");
    }
    for (int i = 0; i < 3; ++i) m.principal_variances_(i) = r.Get<double>("principal_variances");
    m.points_ = r.GetArray<Eigen::Vector3d>("points");
    m.normals_ = r.GetArray<Eigen::Vector3d>("normals");
    auto refinement = r.GetArray<Eigen::Vector3d>("refinement_points");
    m.refinement_normals_ = r.GetArray<Eigen::Vector3d>("refinement_normals");
    m.keys_ = r.GetArray<std::uint32_t>("keys");
    m.offsets_ = r.GetArray<std::uint32_t>("offsets");
    m.entries_ = r.GetArray<PpfPairEntry>("entries");
    if (r.position() + sizeof(std::uint64_t) != bytes.size())
      r.Fail("unexpected bytes after the pair table");
    Validate(m, refinement.size(), r);
    m.refinement_tree_ = KdTree(std::move(refinement));
    m.BuildDenseIndex();
    return m;
  }

 private:
  // Structural checks so a decoded model can never index out of bounds.
  static void Validate(const PpfModel& m, std::size_t refinement_size, const io::RawReader& r) {
    if (!(m.distance_step_mm_ > 0.0) || !(m.angle_step_rad_ > 0.0) || m.distance_bins_ < 1 ||
        m.angle_bins_ < 1 || m.alpha_bins_ < 1 || m.distance_bins_ > (1 << 25) ||
        m.angle_bins_ > 180 || m.points_.size() > 65535) {
      r.Fail("quantization fields out of range");
    }
    const auto a = static_cast<std::size_t>(m.angle_bins_);
    const std::size_t key_space = static_cast<std::size_t>(m.distance_bins_) * a * a * a;
    if (key_space > (std::size_t{1} << 25)) r.Fail("key space too large");
    if (m.normals_.size() != m.points_.size() || m.refinement_normals_.size() != refinement_size)
      r.Fail("normals do not match points");
    if (m.offsets_.size() != m.keys_.size() + 1 || m.offsets_.front() != 0 ||
        m.offsets_.back() != m.entries_.size()) {
      r.Fail("offsets do not match the pair table");
    }
    for (std::size_t k = 0; k < m.keys_.size(); ++k) {
      if (m.keys_[k] >= key_space || (k > 0 && m.keys_[k] <= m.keys_[k - 1]) ||
          m.offsets_[k + 1] < m.offsets_[k]) {
        r.Fail("pair table keys are not sorted or out of range");
      }
    }
    for (const PpfPairEntry& e : m.entries_) {
      if (e.reference >= m.points_.size()) r.Fail("pair entry references a missing point");
    }
  }
};

std::string PpfModel::Serialize() const { return PpfModelCodec::Encode(*this); }

PpfModel PpfModel::Deserialize(std::string_view bytes, const std::string& name) {
  return PpfModelCodec::Decode(bytes, name);
}

void PpfModel::Save(const std::string& path) const { io::WriteFileAtomically(path, Serialize()); }

PpfModel PpfModel::Load(const std::string& path) {
  return Deserialize(io::ReadFileBytes(path), path);
}

}  // namespace lasercell::registration
