#pragma once
// Reassembling sweeps from profile datagrams (udp_packet.hpp), without sockets: the receiver
// (udp_stream.hpp) feeds every datagram with its arrival time and takes finished sweeps. Time is
// passed in, so tests drive it deterministically.
//
// Rules:
//  - A profile is delivered only when every fragment arrived and all agree (sequence, timestamp,
//    joints, geometry); it keeps its own sequence number, timestamp and joint values. A lost
//    profile is a gap in the sweep's sequence numbers, never filled from a neighbour.
//  - At most `reorder_window` profiles are in reassembly at once; when one more starts, the
//    oldest is given up as incomplete and its memory freed. Fragments of a profile already
//    delivered are duplicates; of a profile given up, late; both are dropped and counted.
//  - A sweep ends when its END arrived and every profile it announces is complete, or
//    `end_grace_ms` after its END, or when no datagram of it arrived for `sweep_timeout_ms`.
//  - Datagrams of a sweep that ended are stale (counted, dropped) for 2 x sweep_timeout_ms after
//    its last datagram; after that a sender may use the same sweep number again.
//  - Each finished sweep comes with its loss account: missing sequence ranges (nothing
//    arrived), incomplete profiles (some fragments arrived), duplicates, late fragments.

#include <array>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "triangulation/profile_io.hpp"
#include "triangulation/udp_packet.hpp"

namespace lasercell::triangulation {

/// How sweeps are reassembled. Memory is bounded by reorder_window profiles in reassembly plus
/// max_sweep_profiles delivered profiles per open sweep (at most max_open_sweeps).
struct SweepAssemblyOptions {
  DatagramLimits limits;            ///< Datagrams beyond these are refused.
  std::int64_t sensor_id = -1;      ///< Only this sensor's datagrams; -1 = any sensor.
  std::size_t reorder_window = 64;  ///< Profiles in reassembly at once (>= 1).
  double end_grace_ms = 20.0;       ///< How long after END stragglers may complete a sweep.
  double sweep_timeout_ms = 500.0;  ///< A sweep with no datagram for this long ends.
  /// Profiles kept per sweep; more are dropped, counted and listed among the missing.
  std::size_t max_sweep_profiles = 100000;
  std::size_t max_open_sweeps = 4;  ///< Sweeps open at once; a new one ends the oldest.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// Why a sweep ended.
enum class SweepEnd : std::uint8_t {
  kComplete,    ///< END arrived and every announced profile is complete.
  kEndGrace,    ///< END arrived; end_grace_ms passed with profiles still missing.
  kTimeout,     ///< No END; no datagram for sweep_timeout_ms.
  kSuperseded,  ///< Closed to make room for a newer sweep (max_open_sweeps), or flushed.
};
/// "complete", "end_grace", "timeout", "superseded".
const char* SweepEndName(SweepEnd end);

/// An inclusive range of sequence numbers.
struct SequenceRange {
  std::uint64_t first = 0;
  std::uint64_t last = 0;
  bool operator==(const SequenceRange&) const = default;
};
/// "17, 40-42, ..." (at most `shown` ranges, then "...").
std::string SequenceRangesText(const std::vector<SequenceRange>& ranges, std::size_t shown = 4);

/// What one sweep lost, and why it ended.
struct SweepAccount {
  std::uint32_t sensor_id = 0;
  std::uint32_t sweep_id = 0;
  std::uint64_t first_sequence = 0;  ///< From BEGIN/END, else the lowest seen.
  std::uint64_t last_sequence = 0;   ///< From END, else the highest seen.
  bool begin_received = false;
  bool end_received = false;
  std::int64_t sent_profiles = -1;         ///< What END says the sender sent; -1 without END.
  std::size_t delivered = 0;               ///< Complete profiles in the sweep.
  std::vector<SequenceRange> missing;      ///< Sequences of which nothing arrived.
  std::vector<std::uint64_t> incomplete;   ///< Sequences of which some fragments arrived.
  std::size_t duplicate_fragments = 0;     ///< Fragments that arrived again.
  std::size_t late_fragments = 0;          ///< Fragments of profiles already given up.
  std::size_t inconsistent_fragments = 0;  ///< Fragments that disagree with their profile.
  std::size_t overflow_profiles = 0;       ///< Complete profiles over max_sweep_profiles.
  SweepEnd ended_by = SweepEnd::kTimeout;
  /// Number of sequences in `missing`.
  std::uint64_t MissingCount() const;
  /// One line, e.g. "sweep 3 of sensor 1: 998 profiles, missing 2 (17, 40-40), 1 incomplete,
  /// 4 duplicates, ended by END".
  std::string Summary() const;
};

/// The account as JSON: every field, missing ranges as [first, last] pairs, ended_by by name.
nlohmann::json SweepAccountJson(const SweepAccount& account);

/// A finished sweep and its account.
struct AssembledSweep {
  ProfileSet set;  ///< Complete profiles in sequence order.
  SweepAccount account;
};

/// Counts over everything fed, since construction.
struct StreamCounters {
  std::uint64_t datagrams = 0;  ///< Datagrams fed.
  std::uint64_t bytes = 0;      ///< Their bytes.
  /// Refused datagrams per DatagramStatus (index kOk unused).
  std::array<std::uint64_t, static_cast<std::size_t>(DatagramStatus::kCount)> refused{};
  std::uint64_t other_sensor = 0;  ///< Valid datagrams of a sensor not listened to.
  std::uint64_t stale = 0;         ///< Datagrams of a sweep that already ended.
  std::uint64_t inconsistent = 0;  ///< Datagrams that disagree with their sweep's geometry.
  std::uint64_t sweeps_finished = 0;
  std::uint64_t kernel_dropped = 0;  ///< Datagrams the OS dropped (socket buffer full).
  std::size_t peak_reassembly = 0;   ///< Most profiles in reassembly at once.
  /// Sum of refused.
  std::uint64_t Refused() const;
  /// One line.
  std::string Summary() const;
};

/// The counters as JSON, refused datagrams by reason name.
nlohmann::json StreamCountersJson(const StreamCounters& counters);

/// Reassembles sweeps from datagrams. Not thread-safe; one per receiving socket.
class SweepAssembler {
 public:
  /// Throws OptionError for invalid options.
  explicit SweepAssembler(const SweepAssemblyOptions& options = {});
  ~SweepAssembler();
  SweepAssembler(const SweepAssembler&) = delete;
  SweepAssembler& operator=(const SweepAssembler&) = delete;

  /// Takes one datagram that arrived at `now_ns` (any monotonic clock). Never throws for bad
  /// bytes: they are counted and dropped.
  void Feed(std::string_view datagram, std::int64_t now_ns);
  /// The sweep that finished first by `now_ns`, if any (call until nullopt).
  std::optional<AssembledSweep> TakeFinished(std::int64_t now_ns);
  /// Ends every open sweep (kSuperseded unless complete) and returns them, oldest first.
  std::vector<AssembledSweep> Flush();
  /// When the next open sweep may end by time (its grace or timeout); a time in the past when a
  /// finished sweep is waiting; nullopt with none open.
  std::optional<std::int64_t> NextDeadlineNs() const;
  /// Number of sweeps open.
  std::size_t open_sweeps() const;
  const StreamCounters& counters() const { return counters_; }
  /// Adds to counters().kernel_dropped (the receiver reads it from the socket).
  void AddKernelDropped(std::uint64_t n) { counters_.kernel_dropped += n; }

 private:
  struct Sweep;
  Sweep* FindOrOpen(const Datagram& d, std::int64_t now_ns);
  void FeedFragment(Sweep& sweep, const Datagram& d);
  void FeedMarker(Sweep& sweep, const Datagram& d, std::int64_t now_ns);
  AssembledSweep Close(std::size_t index, SweepEnd end);
  bool Finished(const Sweep& sweep, std::int64_t now_ns, SweepEnd* end) const;

  SweepAssemblyOptions options_;
  StreamCounters counters_;
  std::vector<std::unique_ptr<Sweep>> open_;
  std::deque<AssembledSweep> ready_;  // closed to make room, not yet taken
  struct ClosedSweep {
    std::uint32_t sensor_id, sweep_id;
    std::int64_t last_activity_ns;
  };
  std::deque<ClosedSweep> closed_;  // recently ended
};

}  // namespace lasercell::triangulation
