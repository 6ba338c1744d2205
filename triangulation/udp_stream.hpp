#pragma once
// Profiles over UDP (udp_packet.hpp): a receiving profile source for jobs and recorders, and a
// sender that replays a profile file at the sensor's rate, optionally through seeded
// impairments (loss, reordering, duplication) so tests know exactly what the network did.
// IPv4; addresses as "HOST:PORT" (a dotted address or a name the resolver knows).

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "triangulation/profile_source.hpp"
#include "triangulation/udp_assembler.hpp"
#include "triangulation/udp_packet.hpp"

namespace lasercell::triangulation {

/// Options of UdpProfileSource.
struct UdpSourceOptions {
  std::string bind_address = "0.0.0.0";  ///< Interface to listen on ("127.0.0.1": loopback).
  std::uint16_t port = 0;                ///< UDP port; 0 = any free port (see port()).
  /// Socket receive buffer, bytes: absorbs bursts while a sweep is handed over. As root the
  /// system limit is bypassed (SO_RCVBUFFORCE), otherwise net.core.rmem_max caps it.
  int receive_buffer_bytes = 16 << 20;
  /// NextSweep returns nullopt when no datagram arrives for this long and no sweep is open,
  /// ms; 0 = wait for ever.
  double idle_timeout_ms = 0.0;
  SweepAssemblyOptions assembly;  ///< Reassembly rules and bounds.
  /// Throws OptionError naming the field.
  void Check() const;
};

/// A profile source that listens on a UDP port and delivers each sweep as it ends, with its
/// loss account (last_account()). Lost profiles are gaps in the sequence numbers.
class UdpProfileSource : public ProfileSource {
 public:
  /// Opens and binds the socket. Throws InputError naming the address when it cannot be bound
  /// (in use, not an address of this machine).
  explicit UdpProfileSource(const UdpSourceOptions& options);
  ~UdpProfileSource() override;
  UdpProfileSource(const UdpProfileSource&) = delete;
  UdpProfileSource& operator=(const UdpProfileSource&) = delete;

  /// The next sweep that ends (see udp_assembler.hpp), or nullopt after idle_timeout_ms of
  /// silence or when Stop() was called.
  std::optional<ProfileSet> NextSweep() override;
  /// The next sweep with its account.
  std::optional<AssembledSweep> NextAssembledSweep();
  /// E.g. "udp 127.0.0.1:5000".
  std::string Describe() const override;
  /// The last sweep's account summary when it lost profiles or fragments, else "".
  std::string LastSweepLoss() const override;
  /// The bound port (the one chosen when options.port was 0).
  std::uint16_t port() const { return port_; }
  /// The account of the sweep NextSweep returned last; nullptr before the first.
  const SweepAccount* last_account() const { return last_ ? &*last_ : nullptr; }
  /// Counters since construction.
  const StreamCounters& counters() const { return assembler_.counters(); }
  /// Makes a waiting NextSweep return nullopt within ~50 ms (callable from another thread).
  void Stop() { stop_ = true; }

 private:
  void ReceiveBatch();

  UdpSourceOptions options_;
  int fd_ = -1;
  std::uint16_t port_ = 0;
  SweepAssembler assembler_;
  std::optional<SweepAccount> last_;
  std::atomic<bool> stop_{false};
  std::uint32_t kernel_dropped_seen_ = 0;
  struct Buffers;
  std::unique_ptr<Buffers> buffers_;
};

/// Seeded network impairments applied by the sender (tests and demonstrations).
struct Impairments {
  double loss = 0.0;              ///< Probability that a datagram is not sent.
  double reorder = 0.0;           ///< Probability that a datagram is held back behind later ones.
  double duplicate = 0.0;         ///< Probability that a datagram is sent twice.
  std::size_t reorder_depth = 8;  ///< A held-back datagram goes after 1..reorder_depth others.
  std::uint64_t seed = 1;         ///< Seed of the draws.
  /// Throws OptionError naming the field (probabilities in [0, 1)).
  void Check() const;
  /// True when nothing is impaired.
  bool None() const { return loss == 0.0 && reorder == 0.0 && duplicate == 0.0; }
};

/// The send order of `count` datagrams under impairments: indices into the datagram list,
/// duplicated ones repeated, dropped ones absent.
struct ImpairedOrder {
  std::vector<std::size_t> order;
  std::vector<std::size_t> dropped;  ///< Sorted.
  std::size_t reordered = 0;
  std::size_t duplicated = 0;
};
/// Draws the impairments for `count` datagrams (deterministic for a seed).
ImpairedOrder ImpairDatagrams(std::size_t count, const Impairments& impairments);

/// What a sender did to one sweep: what a receiver's account must show.
struct SentAccount {
  std::size_t profiles = 0;        ///< Profiles in the sweep.
  std::size_t datagrams_sent = 0;  ///< Including duplicates.
  std::size_t datagrams_dropped = 0;
  std::size_t reordered = 0;
  std::size_t duplicated = 0;
  std::vector<std::uint64_t> lost_profiles;     ///< Every fragment dropped.
  std::vector<std::uint64_t> partial_profiles;  ///< Some fragments dropped.
  bool begin_dropped = false;
  bool end_dropped = false;
  /// One line.
  std::string Summary() const;
};
/// The account as JSON.
nlohmann::json SentAccountJson(const SentAccount& account);
/// The account of sending `datagrams` of `set` in `order`.
SentAccount AccountSent(const ProfileSet& set, const SweepDatagrams& datagrams,
                        const ImpairedOrder& order);

/// Options of SendSweep.
struct SendOptions {
  double rate_hz = 0.0;  ///< Profiles per second (the sensor's rate); 0 = as fast as possible.
  DatagramOptions datagram;
  Impairments impairments;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// A UDP socket aimed at one receiver.
class UdpSender {
 public:
  /// Resolves "HOST:PORT". Throws InputError naming the address when it cannot be used.
  explicit UdpSender(const std::string& host_port);
  ~UdpSender();
  UdpSender(const UdpSender&) = delete;
  UdpSender& operator=(const UdpSender&) = delete;
  /// Sends datagrams in order (batched; runs of equal-sized datagrams as one UDP GSO send where
  /// the kernel offers it, each still its own datagram on the wire); throws FileError naming
  /// the address on a socket error.
  void Send(const std::vector<const std::string*>& datagrams);
  const std::string& address() const { return address_; }

 private:
  int fd_ = -1;
  std::string address_;
  bool gso_ = true;  // UDP_SEGMENT batching, until the kernel refuses it
};

/// Sends encoded datagrams in `order` (ImpairDatagrams), paced so that profile k leaves k /
/// rate_hz seconds after the first (rate_hz 0: as fast as possible). Returns the number sent;
/// stops early when `stop` becomes true.
std::size_t SendDatagrams(UdpSender& sender, const SweepDatagrams& datagrams,
                          const ImpairedOrder& order, double rate_hz,
                          const std::atomic<bool>* stop = nullptr);

/// Sends one sweep, paced at options.rate_hz, through options.impairments. Stops early (and
/// says so in the account's datagrams_sent) when `stop` becomes true.
SentAccount SendSweep(UdpSender& sender, const ProfileSet& set, const SendOptions& options,
                      const std::atomic<bool>* stop = nullptr);

}  // namespace lasercell::triangulation
