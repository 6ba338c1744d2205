#include "triangulation/udp_assembler.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <set>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"

namespace lasercell::triangulation {

namespace {

constexpr std::size_t kRememberClosed = 16;

std::int64_t MsToNs(double ms) { return static_cast<std::int64_t>(std::llround(ms * 1e6)); }

// A profile in reassembly: which fragments and columns arrived.
struct Pending {
  Profile profile;
  std::vector<bool> got;      // per fragment
  std::vector<bool> covered;  // per column: fragments must tile the profile without overlap
  std::uint16_t received = 0;
  std::uint16_t fragment_count = 0;
};

// Bit-exact comparison of a fragment's joints with the profile's (NaN joints compare equal to
// themselves; a sender repeats the same values in every fragment).
bool SameJoints(const Datagram& d, const std::vector<double>& joints) {
  if (d.joint_count != joints.size()) return false;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const double v = io::GetLe<double>(d.joints + 8 * j);
    if (std::memcmp(&v, &joints[j], sizeof v) != 0) return false;
  }
  return true;
}

bool SameGeometry(const ProfileHeader& h, const Datagram& d) {
  return h.columns == d.columns && h.first_column == d.first_column &&
         h.image_width == d.image_width && h.image_height == d.image_height &&
         h.joint_count == d.joint_count;
}

bool SameGeometry(const ProfileHeader& a, const ProfileHeader& b) {
  return a.columns == b.columns && a.first_column == b.first_column &&
         a.image_width == b.image_width && a.image_height == b.image_height &&
         a.joint_count == b.joint_count;
}

}  // namespace

struct SweepAssembler::Sweep {
  std::uint32_t sensor_id = 0;
  std::uint32_t sweep_id = 0;
  bool geometry_known = false;
  ProfileHeader header;
  bool begin_received = false;
  bool end_received = false;
  std::optional<std::uint64_t> first, last;  // from BEGIN / END
  std::int64_t sent_profiles = -1;
  std::uint64_t min_seen = UINT64_MAX, max_seen = 0;
  std::map<std::uint64_t, Profile> complete;
  std::map<std::uint64_t, Pending> pending;
  std::set<std::uint64_t> incomplete;
  std::int64_t last_activity_ns = 0;
  std::int64_t end_ns = 0;
  SweepAccount account;  // counters filled while feeding
};

void SweepAssemblyOptions::Check() const {
  const auto bad = [](const std::string& field, const std::string& rule) {
    return OptionError("SweepAssemblyOptions." + field + " " + rule);
  };
  if (limits.max_columns == 0 || limits.max_fragments == 0) {
    throw bad("limits", "max_columns and max_fragments must be > 0");
  }
  if (reorder_window == 0) throw bad("reorder_window", "must be >= 1");
  if (!(end_grace_ms >= 0.0) || !std::isfinite(end_grace_ms)) {
    throw bad("end_grace_ms", "must be finite and >= 0");
  }
  if (!(sweep_timeout_ms > 0.0) || !std::isfinite(sweep_timeout_ms)) {
    throw bad("sweep_timeout_ms", "must be finite and > 0");
  }
  if (max_sweep_profiles == 0) throw bad("max_sweep_profiles", "must be >= 1");
  if (max_open_sweeps == 0) throw bad("max_open_sweeps", "must be >= 1");
  if (sensor_id < -1 || sensor_id > static_cast<std::int64_t>(UINT32_MAX)) {
    throw bad("sensor_id", "must be -1 (any) or a u32 sensor id");
  }
}

const char* SweepEndName(SweepEnd end) {
  switch (end) {
    case SweepEnd::kComplete:
      return "complete";
    case SweepEnd::kEndGrace:
      return "end_grace";
    case SweepEnd::kTimeout:
      return "timeout";
    case SweepEnd::kSuperseded:
      return "superseded";
  }
  return "unknown";
}

std::uint64_t SweepAccount::MissingCount() const {
  std::uint64_t n = 0;
  for (const SequenceRange& r : missing) n += r.last - r.first + 1;
  return n;
}

std::string SequenceRangesText(const std::vector<SequenceRange>& ranges, std::size_t shown) {
  std::string s;
  for (std::size_t i = 0; i < ranges.size() && i < shown; ++i) {
    if (i > 0) s += ", ";
    s += std::to_string(ranges[i].first);
    if (ranges[i].last != ranges[i].first) {
      s += '-';
      s += std::to_string(ranges[i].last);
    }
  }
  if (ranges.size() > shown) s += ", ...";
  return s;
}

std::string SweepAccount::Summary() const {
  std::string s = "sweep " + std::to_string(sweep_id) + " of sensor " + std::to_string(sensor_id) +
                  ": " + std::to_string(delivered) + " profiles";
  if (sent_profiles >= 0) s += " of " + std::to_string(sent_profiles) + " sent";
  s += ", " + std::to_string(MissingCount()) + " missing";
  if (!missing.empty()) s += " (" + SequenceRangesText(missing) + ")";
  s += ", " + std::to_string(incomplete.size()) + " incomplete, " +
       std::to_string(duplicate_fragments) + " duplicate and " + std::to_string(late_fragments) +
       " late fragments";
  if (inconsistent_fragments > 0) {
    s += ", " + std::to_string(inconsistent_fragments) + " inconsistent";
  }
  if (overflow_profiles > 0) s += ", " + std::to_string(overflow_profiles) + " over the limit";
  if (!begin_received && !end_received) s += ", no BEGIN/END (robot and metadata unknown)";
  return s + "; ended: " + SweepEndName(ended_by);
}

nlohmann::json SweepAccountJson(const SweepAccount& a) {
  nlohmann::json missing = nlohmann::json::array();
  for (const SequenceRange& r : a.missing) missing.push_back({r.first, r.last});
  return {{"sensor_id", a.sensor_id},
          {"sweep_id", a.sweep_id},
          {"first_sequence", a.first_sequence},
          {"last_sequence", a.last_sequence},
          {"begin_received", a.begin_received},
          {"end_received", a.end_received},
          {"sent_profiles", a.sent_profiles},
          {"delivered", a.delivered},
          {"missing_count", a.MissingCount()},
          {"missing", missing},
          {"incomplete", a.incomplete},
          {"duplicate_fragments", a.duplicate_fragments},
          {"late_fragments", a.late_fragments},
          {"inconsistent_fragments", a.inconsistent_fragments},
          {"overflow_profiles", a.overflow_profiles},
          {"ended_by", SweepEndName(a.ended_by)}};
}

nlohmann::json StreamCountersJson(const StreamCounters& c) {
  nlohmann::json refused = nlohmann::json::object();
  for (std::size_t i = 1; i < c.refused.size(); ++i) {
    refused[DatagramStatusName(static_cast<DatagramStatus>(i))] = c.refused[i];
  }
  return {{"datagrams", c.datagrams},
          {"bytes", c.bytes},
          {"refused", refused},
          {"other_sensor", c.other_sensor},
          {"stale", c.stale},
          {"inconsistent", c.inconsistent},
          {"sweeps_finished", c.sweeps_finished},
          {"kernel_dropped", c.kernel_dropped},
          {"peak_reassembly", c.peak_reassembly}};
}

std::uint64_t StreamCounters::Refused() const {
  std::uint64_t n = 0;
  for (std::uint64_t r : refused) n += r;
  return n;
}

std::string StreamCounters::Summary() const {
  std::string s = std::to_string(datagrams) + " datagrams (" + std::to_string(bytes) + " bytes), " +
                  std::to_string(sweeps_finished) + " sweeps, " + std::to_string(Refused()) +
                  " refused";
  std::string why;
  for (std::size_t i = 1; i < refused.size(); ++i) {
    if (refused[i] == 0) continue;
    why += (why.empty() ? "" : ", ") +
           std::string(DatagramStatusName(static_cast<DatagramStatus>(i))) + " " +
           std::to_string(refused[i]);
  }
  if (!why.empty()) s += " (" + why + ")";
  s += ", " + std::to_string(other_sensor) + " of other sensors, " + std::to_string(stale) +
       " stale, " + std::to_string(inconsistent) + " inconsistent, " +
       std::to_string(kernel_dropped) + " dropped by the OS";
  return s;
}

SweepAssembler::SweepAssembler(const SweepAssemblyOptions& options) : options_(options) {
  options_.Check();
}

SweepAssembler::~SweepAssembler() = default;

std::size_t SweepAssembler::open_sweeps() const { return open_.size(); }

SweepAssembler::Sweep* SweepAssembler::FindOrOpen(const Datagram& d, std::int64_t now_ns) {
  for (auto& s : open_) {
    if (s->sensor_id == d.sensor_id && s->sweep_id == d.sweep_id) return s.get();
  }
  // A datagram of a sweep that ended is stale for 2 x sweep_timeout_ms after the sweep's last
  // datagram (stragglers, duplicates of END); later, the same number starts a new sweep.
  const std::int64_t stale_ns = 2 * MsToNs(options_.sweep_timeout_ms);
  for (const ClosedSweep& c : closed_) {
    if (c.sensor_id == d.sensor_id && c.sweep_id == d.sweep_id &&
        now_ns - c.last_activity_ns < stale_ns) {
      ++counters_.stale;
      return nullptr;
    }
  }
  if (open_.size() >= options_.max_open_sweeps) {
    // Room for the new sweep: the least recently active one ends (its account says so).
    std::size_t oldest = 0;
    for (std::size_t i = 1; i < open_.size(); ++i) {
      if (open_[i]->last_activity_ns < open_[oldest]->last_activity_ns) oldest = i;
    }
    ready_.push_back(Close(oldest, SweepEnd::kSuperseded));
  }
  auto sweep = std::make_unique<Sweep>();
  sweep->sensor_id = d.sensor_id;
  sweep->sweep_id = d.sweep_id;
  sweep->last_activity_ns = now_ns;
  open_.push_back(std::move(sweep));
  return open_.back().get();
}

void SweepAssembler::Feed(std::string_view datagram, std::int64_t now_ns) {
  ++counters_.datagrams;
  counters_.bytes += datagram.size();
  Datagram d;
  DatagramStatus status = DecodeDatagram(datagram, options_.limits, &d);
  if (status == DatagramStatus::kOk && d.type != DatagramType::kFragment &&
      (d.header.columns > options_.limits.max_columns ||
       d.header.joint_count > options_.limits.max_joints)) {
    status = DatagramStatus::kBadColumns;
  }
  if (status != DatagramStatus::kOk) {
    ++counters_.refused[static_cast<std::size_t>(status)];
    return;
  }
  if (options_.sensor_id >= 0 && d.sensor_id != static_cast<std::uint32_t>(options_.sensor_id)) {
    ++counters_.other_sensor;
    return;
  }
  Sweep* sweep = FindOrOpen(d, now_ns);
  if (sweep == nullptr) return;
  sweep->last_activity_ns = now_ns;
  if (d.type == DatagramType::kFragment) {
    FeedFragment(*sweep, d);
  } else {
    FeedMarker(*sweep, d, now_ns);
  }
}

void SweepAssembler::FeedMarker(Sweep& sweep, const Datagram& d, std::int64_t now_ns) {
  if (sweep.geometry_known && !SameGeometry(sweep.header, d.header)) {
    ++counters_.inconsistent;
    ++sweep.account.inconsistent_fragments;
    return;
  }
  sweep.header = d.header;
  sweep.geometry_known = true;
  sweep.first = d.sequence;
  if (d.type == DatagramType::kBegin) {
    sweep.begin_received = true;
    return;
  }
  if (!sweep.end_received) sweep.end_ns = now_ns;
  sweep.end_received = true;
  sweep.last = d.last_sequence;
  sweep.sent_profiles = static_cast<std::int64_t>(d.profile_count);
}

void SweepAssembler::FeedFragment(Sweep& sweep, const Datagram& d) {
  if (!sweep.geometry_known) {
    sweep.header.columns = d.columns;
    sweep.header.first_column = d.first_column;
    sweep.header.image_width = d.image_width;
    sweep.header.image_height = d.image_height;
    sweep.header.joint_count = d.joint_count;
    sweep.geometry_known = true;
  } else if (!SameGeometry(sweep.header, d)) {
    ++counters_.inconsistent;
    ++sweep.account.inconsistent_fragments;
    return;
  }
  SweepAccount& acc = sweep.account;
  const std::uint64_t seq = d.sequence;
  if (sweep.complete.count(seq) != 0) {
    ++acc.duplicate_fragments;
    return;
  }
  if (sweep.incomplete.count(seq) != 0) {
    ++acc.late_fragments;
    return;
  }
  auto it = sweep.pending.find(seq);
  if (it == sweep.pending.end()) {
    if (sweep.pending.size() >= options_.reorder_window) {
      // The oldest profile in reassembly is given up (Rules: reorder window).
      sweep.incomplete.insert(sweep.pending.begin()->first);
      sweep.pending.erase(sweep.pending.begin());
    }
    Pending p;
    p.profile = Profile::Empty(d.columns, d.joint_count);
    p.profile.sequence = seq;
    p.profile.timestamp_ns = d.timestamp_ns;
    for (std::size_t j = 0; j < d.joint_count; ++j) {
      p.profile.joints_rad[j] = io::GetLe<double>(d.joints + 8 * j);
    }
    p.got.assign(d.fragment_count, false);
    p.covered.assign(d.columns, false);
    p.fragment_count = d.fragment_count;
    it = sweep.pending.emplace(seq, std::move(p)).first;
    counters_.peak_reassembly = std::max(counters_.peak_reassembly, sweep.pending.size());
  }
  Pending& p = it->second;
  if (d.fragment_count != p.fragment_count || d.timestamp_ns != p.profile.timestamp_ns ||
      !SameJoints(d, p.profile.joints_rad)) {
    ++counters_.inconsistent;
    ++acc.inconsistent_fragments;
    return;
  }
  if (p.got[d.fragment_index]) {
    ++acc.duplicate_fragments;
    return;
  }
  const auto c0 = p.covered.begin() + d.column_offset;
  if (std::find(c0, c0 + d.column_count, true) != c0 + d.column_count) {
    ++counters_.inconsistent;
    ++acc.inconsistent_fragments;
    return;
  }
  std::fill(c0, c0 + d.column_count, true);
  p.got[d.fragment_index] = true;
  ++p.received;
  CopyFragmentColumns(d, &p.profile);
  sweep.min_seen = std::min(sweep.min_seen, seq);
  sweep.max_seen = std::max(sweep.max_seen, seq);
  if (p.received < p.fragment_count) return;
  if (std::find(p.covered.begin(), p.covered.end(), false) != p.covered.end()) {
    // Every fragment arrived but they leave columns uncovered: the sender's split is broken.
    ++acc.inconsistent_fragments;
    sweep.incomplete.insert(seq);
  } else if (sweep.complete.size() >= options_.max_sweep_profiles) {
    ++acc.overflow_profiles;
  } else {
    sweep.complete.emplace(seq, std::move(p.profile));
  }
  sweep.pending.erase(it);
}

bool SweepAssembler::Finished(const Sweep& sweep, std::int64_t now_ns, SweepEnd* end) const {
  if (sweep.end_received) {
    if (sweep.pending.empty() &&
        static_cast<std::int64_t>(sweep.complete.size()) >= sweep.sent_profiles) {
      *end = SweepEnd::kComplete;
      return true;
    }
    if (now_ns >= sweep.end_ns + MsToNs(options_.end_grace_ms)) {
      *end = SweepEnd::kEndGrace;
      return true;
    }
  }
  if (now_ns >= sweep.last_activity_ns + MsToNs(options_.sweep_timeout_ms)) {
    *end = SweepEnd::kTimeout;
    return true;
  }
  return false;
}

AssembledSweep SweepAssembler::Close(std::size_t index, SweepEnd end) {
  Sweep& sweep = *open_[index];
  for (const auto& [seq, p] : sweep.pending) sweep.incomplete.insert(seq);
  sweep.pending.clear();
  SweepAccount acc = sweep.account;
  acc.sensor_id = sweep.sensor_id;
  acc.sweep_id = sweep.sweep_id;
  acc.begin_received = sweep.begin_received;
  acc.end_received = sweep.end_received;
  acc.sent_profiles = sweep.sent_profiles;
  acc.ended_by = end;
  const bool seen = sweep.min_seen <= sweep.max_seen;
  std::uint64_t first = sweep.first.value_or(seen ? sweep.min_seen : 0);
  std::uint64_t last = sweep.last.value_or(seen ? sweep.max_seen : first);
  if (seen) {
    first = std::min(first, sweep.min_seen);
    last = std::max(last, sweep.max_seen);
  }
  acc.first_sequence = first;
  acc.last_sequence = last;
  acc.incomplete.assign(sweep.incomplete.begin(), sweep.incomplete.end());
  // Missing: sequences in [first, last] that are neither delivered nor incomplete. Both key
  // sets are sorted; walk them together.
  if (seen || sweep.last.has_value()) {
    std::uint64_t next = first;  // lowest sequence not yet accounted for
    bool exhausted = false;      // next would pass UINT64_MAX
    const auto arrived = [&](std::uint64_t seq) {
      if (exhausted || seq < next) return;
      if (seq > next) acc.missing.push_back({next, seq - 1});
      exhausted = seq == UINT64_MAX;
      next = seq + 1;
    };
    auto c = sweep.complete.begin();
    auto i = sweep.incomplete.begin();
    while (c != sweep.complete.end() || i != sweep.incomplete.end()) {
      if (i == sweep.incomplete.end() || (c != sweep.complete.end() && c->first < *i)) {
        arrived((c++)->first);
      } else {
        arrived(*(i++));
      }
    }
    if (!exhausted && next <= last) acc.missing.push_back({next, last});
  }
  AssembledSweep out;
  out.set.header = sweep.header;
  out.set.profiles.reserve(sweep.complete.size());
  for (auto& [seq, prof] : sweep.complete) out.set.profiles.push_back(std::move(prof));
  acc.delivered = out.set.profiles.size();
  out.account = std::move(acc);
  closed_.push_back({sweep.sensor_id, sweep.sweep_id, sweep.last_activity_ns});
  if (closed_.size() > kRememberClosed) closed_.pop_front();
  open_.erase(open_.begin() + static_cast<std::ptrdiff_t>(index));
  ++counters_.sweeps_finished;
  return out;
}

std::optional<AssembledSweep> SweepAssembler::TakeFinished(std::int64_t now_ns) {
  if (!ready_.empty()) {
    AssembledSweep out = std::move(ready_.front());
    ready_.pop_front();
    return out;
  }
  for (std::size_t i = 0; i < open_.size(); ++i) {
    SweepEnd end;
    if (Finished(*open_[i], now_ns, &end)) return Close(i, end);
  }
  return std::nullopt;
}

std::vector<AssembledSweep> SweepAssembler::Flush() {
  std::vector<AssembledSweep> out;
  while (!ready_.empty()) {
    out.push_back(std::move(ready_.front()));
    ready_.pop_front();
  }
  while (!open_.empty()) {
    SweepEnd end = SweepEnd::kSuperseded;
    const Sweep& s = *open_.front();
    if (s.end_received && s.pending.empty() &&
        static_cast<std::int64_t>(s.complete.size()) >= s.sent_profiles) {
      end = SweepEnd::kComplete;
    }
    out.push_back(Close(0, end));
  }
  return out;
}

std::optional<std::int64_t> SweepAssembler::NextDeadlineNs() const {
  if (!ready_.empty()) return INT64_MIN;
  std::optional<std::int64_t> best;
  for (const auto& s : open_) {
    std::int64_t t = s->last_activity_ns + MsToNs(options_.sweep_timeout_ms);
    if (s->end_received) t = std::min(t, s->end_ns + MsToNs(options_.end_grace_ms));
    if (!best || t < *best) best = t;
  }
  return best;
}

}  // namespace lasercell::triangulation
