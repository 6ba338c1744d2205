#include "triangulation/udp_stream.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/udp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "core/error.hpp"
#include "core/net_address.hpp"
#include "core/steady_time.hpp"

namespace lasercell::triangulation {

namespace {

constexpr std::size_t kBatch = 64;              // datagrams per recvmmsg / sendmmsg
constexpr std::size_t kDatagramBuffer = 65536;  // larger than any UDP/IPv4 payload
constexpr int kStopPollMs = 50;                 // how often a waiting receiver checks Stop()

std::string SystemError(const std::string& what) { return what + ": " + std::strerror(errno); }

}  // namespace

// ------------------------------------------------------------------------------------------
// Receiver

struct UdpProfileSource::Buffers {
  std::vector<char> data = std::vector<char>(kBatch * kDatagramBuffer);
  std::vector<char> control = std::vector<char>(kBatch * CMSG_SPACE(sizeof(std::uint32_t)));
  std::vector<mmsghdr> headers = std::vector<mmsghdr>(kBatch);
  std::vector<iovec> iovs = std::vector<iovec>(kBatch);
};

void UdpSourceOptions::Check() const {
  if (receive_buffer_bytes < 65536) {
    throw OptionError("UdpSourceOptions.receive_buffer_bytes = " +
                      std::to_string(receive_buffer_bytes) + " must be >= 65536");
  }
  if (!(idle_timeout_ms >= 0.0) || !std::isfinite(idle_timeout_ms)) {
    throw OptionError("UdpSourceOptions.idle_timeout_ms must be finite and >= 0 (0 = for ever)");
  }
  assembly.Check();
}

UdpProfileSource::UdpProfileSource(const UdpSourceOptions& options)
    : options_(options), assembler_(options.assembly), buffers_(std::make_unique<Buffers>()) {
  options_.Check();
  const std::string where = options_.bind_address + ":" + std::to_string(options_.port);
  sockaddr_in addr = net::ListenAddress(options_.bind_address, options_.port, "UDP listen address");
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw InputError(SystemError("cannot open a UDP socket for " + where));
  const int size = options_.receive_buffer_bytes;
  if (setsockopt(fd_, SOL_SOCKET, SO_RCVBUFFORCE, &size, sizeof size) != 0) {
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);  // capped by rmem_max
  }
  const int on = 1;
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string message = SystemError("cannot listen on UDP " + where);
    close(fd_);
    throw InputError(message + "; choose another port or stop the program that holds it");
  }
  socklen_t len = sizeof addr;
  getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
  Buffers& b = *buffers_;
  for (std::size_t i = 0; i < kBatch; ++i) {
    b.iovs[i] = {b.data.data() + i * kDatagramBuffer, kDatagramBuffer};
    msghdr& h = b.headers[i].msg_hdr;
    h = msghdr{};
    h.msg_iov = &b.iovs[i];
    h.msg_iovlen = 1;
  }
}

UdpProfileSource::~UdpProfileSource() {
  if (fd_ >= 0) close(fd_);
}

std::string UdpProfileSource::Describe() const {
  return "udp " + options_.bind_address + ":" + std::to_string(port_);
}

std::string UdpProfileSource::LastSweepLoss() const {
  if (!last_) return "";
  const SweepAccount& a = *last_;
  const bool lost = !a.missing.empty() || !a.incomplete.empty() || a.overflow_profiles > 0 ||
                    a.ended_by != SweepEnd::kComplete;
  return lost ? a.Summary() : "";
}

void UdpProfileSource::ReceiveBatch() {
  Buffers& b = *buffers_;
  const std::size_t control_bytes = CMSG_SPACE(sizeof(std::uint32_t));
  for (int round = 0; round < 16; ++round) {  // bounded: deadlines are checked in between
    for (std::size_t i = 0; i < kBatch; ++i) {
      msghdr& h = b.headers[i].msg_hdr;
      h.msg_control = b.control.data() + i * control_bytes;
      h.msg_controllen = control_bytes;
      h.msg_flags = 0;
    }
    const int n = recvmmsg(fd_, b.headers.data(), kBatch, MSG_DONTWAIT, nullptr);
    if (n <= 0) return;  // EAGAIN: drained
    const std::int64_t now = SteadyNowNs();
    for (int i = 0; i < n; ++i) {
      msghdr& h = b.headers[i].msg_hdr;
      for (cmsghdr* c = CMSG_FIRSTHDR(&h); c != nullptr; c = CMSG_NXTHDR(&h, c)) {
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
          // The socket's drop count when this datagram was queued; queued in order, so it
          // only grows (a wrap of the 32-bit count is the one decrease).
          std::uint32_t dropped;
          std::memcpy(&dropped, CMSG_DATA(c), sizeof dropped);
          assembler_.AddKernelDropped(dropped - kernel_dropped_seen_);  // modulo 2^32
          kernel_dropped_seen_ = dropped;
        }
      }
      assembler_.Feed(
          {b.data.data() + static_cast<std::size_t>(i) * kDatagramBuffer, b.headers[i].msg_len},
          now);
    }
    if (static_cast<std::size_t>(n) < kBatch) return;
  }
}

std::optional<AssembledSweep> UdpProfileSource::NextAssembledSweep() {
  std::int64_t last_datagram = SteadyNowNs();
  const auto idle_ns = static_cast<std::int64_t>(options_.idle_timeout_ms * 1e6);
  while (!stop_) {
    std::int64_t now = SteadyNowNs();
    if (auto sweep = assembler_.TakeFinished(now)) {
      last_ = sweep->account;
      return sweep;
    }
    std::int64_t wait_ns = std::int64_t{kStopPollMs} * 1000000;
    if (const auto deadline = assembler_.NextDeadlineNs()) {
      wait_ns = std::min(wait_ns, std::max<std::int64_t>(0, *deadline - now));
    } else if (idle_ns > 0) {
      if (now - last_datagram >= idle_ns) return std::nullopt;
      wait_ns = std::min(wait_ns, idle_ns - (now - last_datagram));
    }
    pollfd p{fd_, POLLIN, 0};
    const int ready = poll(&p, 1, static_cast<int>((wait_ns + 999999) / 1000000));
    if (ready > 0) {
      ReceiveBatch();
      last_datagram = SteadyNowNs();
    } else if (ready < 0 && errno != EINTR) {
      throw InputError(SystemError("receiving on " + Describe()));
    }
  }
  return std::nullopt;
}

std::optional<ProfileSet> UdpProfileSource::NextSweep() {
  auto sweep = NextAssembledSweep();
  if (!sweep) return std::nullopt;
  return std::move(sweep->set);
}

// ------------------------------------------------------------------------------------------
// Sender

void Impairments::Check() const {
  const auto probability = [](double p, const char* field) {
    if (!(p >= 0.0 && p < 1.0)) {
      throw OptionError(std::string("Impairments.") + field + " = " + std::to_string(p) +
                        " must be a probability in [0, 1)");
    }
  };
  probability(loss, "loss");
  probability(reorder, "reorder");
  probability(duplicate, "duplicate");
  if (reorder_depth == 0 || reorder_depth > 4096) {
    throw OptionError("Impairments.reorder_depth must be in [1, 4096]");
  }
}

ImpairedOrder ImpairDatagrams(std::size_t count, const Impairments& impairments) {
  impairments.Check();
  std::mt19937_64 rng(impairments.seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::uniform_int_distribution<std::size_t> delay(1, impairments.reorder_depth);
  // Each datagram gets a sort key: its position, pushed back past `delay` others when held
  // back; a duplicate follows its original. Four draws per datagram keep the streams aligned.
  std::vector<std::pair<double, std::size_t>> keyed;
  keyed.reserve(count + count / 16);
  ImpairedOrder out;
  for (std::size_t i = 0; i < count; ++i) {
    const double u_loss = uniform(rng), u_dup = uniform(rng), u_reorder = uniform(rng);
    const std::size_t d = delay(rng);
    if (u_loss < impairments.loss) {
      out.dropped.push_back(i);
      continue;
    }
    double key = static_cast<double>(i);
    if (u_reorder < impairments.reorder) {
      key += static_cast<double>(d) + 0.5;
      ++out.reordered;
    }
    keyed.emplace_back(key, i);
    if (u_dup < impairments.duplicate) {
      keyed.emplace_back(key + 0.25, i);
      ++out.duplicated;
    }
  }
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  out.order.reserve(keyed.size());
  for (const auto& [key, i] : keyed) out.order.push_back(i);
  return out;
}

std::string SentAccount::Summary() const {
  return std::to_string(profiles) + " profiles in " + std::to_string(datagrams_sent) +
         " datagrams; dropped " + std::to_string(datagrams_dropped) + " (" +
         std::to_string(lost_profiles.size()) + " profiles lost, " +
         std::to_string(partial_profiles.size()) + " incomplete" +
         (begin_dropped ? ", BEGIN" : "") + (end_dropped ? ", END" : "") + "), reordered " +
         std::to_string(reordered) + ", duplicated " + std::to_string(duplicated);
}

nlohmann::json SentAccountJson(const SentAccount& a) {
  return {{"profiles", a.profiles},
          {"datagrams_sent", a.datagrams_sent},
          {"datagrams_dropped", a.datagrams_dropped},
          {"reordered", a.reordered},
          {"duplicated", a.duplicated},
          {"lost_profiles", a.lost_profiles},
          {"partial_profiles", a.partial_profiles},
          {"begin_dropped", a.begin_dropped},
          {"end_dropped", a.end_dropped}};
}

SentAccount AccountSent(const ProfileSet& set, const SweepDatagrams& datagrams,
                        const ImpairedOrder& order) {
  SentAccount acc;
  acc.profiles = set.profiles.size();
  acc.datagrams_sent = order.order.size();
  acc.datagrams_dropped = order.dropped.size();
  acc.reordered = order.reordered;
  acc.duplicated = order.duplicated;
  std::vector<std::size_t> total(set.profiles.size(), 0), dropped(set.profiles.size(), 0);
  for (std::int64_t p : datagrams.profile_of) {
    if (p >= 0) ++total[static_cast<std::size_t>(p)];
  }
  for (std::size_t i : order.dropped) {
    const std::int64_t p = datagrams.profile_of[i];
    if (p >= 0) {
      ++dropped[static_cast<std::size_t>(p)];
    } else if (i == 0) {
      acc.begin_dropped = true;
    } else {
      acc.end_dropped = true;
    }
  }
  for (std::size_t p = 0; p < total.size(); ++p) {
    if (dropped[p] == 0) continue;
    (dropped[p] == total[p] ? acc.lost_profiles : acc.partial_profiles)
        .push_back(set.profiles[p].sequence);
  }
  return acc;
}

void SendOptions::Check() const {
  if (!(rate_hz >= 0.0) || !std::isfinite(rate_hz)) {
    throw OptionError("SendOptions.rate_hz must be finite and >= 0 (0 = as fast as possible)");
  }
  datagram.Check();
  impairments.Check();
}

UdpSender::UdpSender(const std::string& host_port) : address_(host_port) {
  const sockaddr_in addr = net::ResolveHostPort(host_port, "UDP destination");
  fd_ = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw InputError(SystemError("cannot open a UDP socket to " + host_port));
  const int size = 4 << 20;
  setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &size, sizeof size);
  if (connect(fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const std::string message = SystemError("cannot send to UDP " + host_port);
    close(fd_);
    throw InputError(message);
  }
}

UdpSender::~UdpSender() {
  if (fd_ >= 0) close(fd_);
}

namespace {

// UDP GSO limits: segments per send and bytes per send (one IPv4 datagram's worth).
constexpr std::size_t kMaxGsoSegments = 64;
constexpr std::size_t kMaxGsoBytes = 65000;

// Runs [first, first + count) of datagrams that one GSO send may carry: equal sizes, and at most
// one shorter datagram at the end (the kernel cuts the payload into gso_size pieces).
std::vector<std::pair<std::size_t, std::size_t>> GsoRuns(const std::vector<const std::string*>& d,
                                                         bool gso) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < d.size();) {
    const std::size_t size = d[i]->size();
    std::size_t n = 1;
    std::size_t bytes = size;
    while (gso && i + n < d.size() && n < kMaxGsoSegments &&
           bytes + d[i + n]->size() <= kMaxGsoBytes && d[i + n]->size() <= size) {
      bytes += d[i + n]->size();
      ++n;
      if (d[i + n - 1]->size() < size) break;  // a shorter one ends the run
    }
    runs.emplace_back(i, n);
    i += n;
  }
  return runs;
}

}  // namespace

// Consecutive datagrams of one size go out as one send with UDP_SEGMENT (Linux >= 4.18): the
// kernel splits it into the same datagrams, so a replay at a sensor's rate costs one system call
// per run instead of one per datagram. A kernel without it gets one datagram per message.
void UdpSender::Send(const std::vector<const std::string*>& datagrams) {
  const auto runs = GsoRuns(datagrams, gso_);
  std::vector<mmsghdr> headers(runs.size());
  std::vector<iovec> iovs(datagrams.size());
  constexpr std::size_t kControl = CMSG_SPACE(sizeof(std::uint16_t));
  std::vector<char> control(runs.size() * kControl, 0);
  for (std::size_t i = 0; i < datagrams.size(); ++i) {
    iovs[i] = {const_cast<char*>(datagrams[i]->data()), datagrams[i]->size()};
  }
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto [first, count] = runs[r];
    headers[r] = mmsghdr{};
    headers[r].msg_hdr.msg_iov = &iovs[first];
    headers[r].msg_hdr.msg_iovlen = count;
    if (count < 2) continue;
    headers[r].msg_hdr.msg_control = &control[r * kControl];
    headers[r].msg_hdr.msg_controllen = kControl;
    cmsghdr* c = CMSG_FIRSTHDR(&headers[r].msg_hdr);
    c->cmsg_level = IPPROTO_UDP;
    c->cmsg_type = UDP_SEGMENT;
    c->cmsg_len = CMSG_LEN(sizeof(std::uint16_t));
    const auto segment = static_cast<std::uint16_t>(datagrams[first]->size());
    std::memcpy(CMSG_DATA(c), &segment, sizeof segment);
  }
  std::size_t done = 0;
  while (done < runs.size()) {
    const int n =
        sendmmsg(fd_, headers.data() + done, static_cast<unsigned>(runs.size() - done), 0);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
    } else if (errno == ECONNREFUSED) {
      ++done;  // nobody listens (yet): UDP does not wait for a receiver
    } else if (gso_ && (errno == EINVAL || errno == EIO || errno == ENOPROTOOPT)) {
      gso_ = false;  // the kernel or the route has no UDP GSO: one datagram per message
      Send({datagrams.begin() + static_cast<std::ptrdiff_t>(runs[done].first), datagrams.end()});
      return;
    } else if (errno != EINTR && errno != ENOBUFS) {
      throw FileError("udp " + address_, std::string("send failed: ") + std::strerror(errno));
    }
  }
}

std::size_t SendDatagrams(UdpSender& sender, const SweepDatagrams& datagrams,
                          const ImpairedOrder& order, double rate_hz,
                          const std::atomic<bool>* stop) {
  std::size_t profiles = 0;
  for (std::int64_t p : datagrams.profile_of) profiles = std::max<std::size_t>(profiles, p + 1);
  const double per_profile =
      profiles == 0 ? 1.0 : static_cast<double>(datagrams.datagrams.size() - 2) / profiles;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<const std::string*> batch;
  std::size_t sent = 0;
  for (std::size_t j = 0; j < order.order.size(); ++j) {
    if (rate_hz > 0.0) {
      // Datagram j is due when the profiles before it would have left a sensor at rate_hz.
      const auto due = t0 + std::chrono::nanoseconds(static_cast<std::int64_t>(
                                std::floor(static_cast<double>(j) / per_profile) / rate_hz * 1e9));
      if (due > std::chrono::steady_clock::now()) {
        sender.Send(batch);
        sent += batch.size();
        batch.clear();
        if (stop != nullptr && *stop) return sent;
        std::this_thread::sleep_until(due);
      }
    }
    batch.push_back(&datagrams.datagrams[order.order[j]]);
    if (batch.size() == kBatch) {
      sender.Send(batch);
      sent += batch.size();
      batch.clear();
      if (stop != nullptr && *stop) return sent;
    }
  }
  sender.Send(batch);
  return sent + batch.size();
}

SentAccount SendSweep(UdpSender& sender, const ProfileSet& set, const SendOptions& options,
                      const std::atomic<bool>* stop) {
  options.Check();
  const SweepDatagrams datagrams = EncodeSweepDatagrams(set, options.datagram);
  const ImpairedOrder order = ImpairDatagrams(datagrams.datagrams.size(), options.impairments);
  SentAccount acc = AccountSent(set, datagrams, order);
  acc.datagrams_sent = SendDatagrams(sender, datagrams, order, options.rate_hz, stop);
  return acc;
}

}  // namespace lasercell::triangulation
