#include "localize/pose_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

#include "core/error.hpp"
#include "core/net_address.hpp"
#include "core/steady_time.hpp"

namespace lasercell::localize {

namespace {

constexpr std::size_t kReadChunk = 4096;
constexpr std::size_t kMaxReadPerTurn = 64 * 1024;  // a flooding client yields to the others

}  // namespace

struct PoseServer::Client {
  enum class Mode { kUnknown, kBinary, kAscii };
  int fd = -1;
  std::string peer;
  Mode mode = Mode::kUnknown;
  std::string in;   // a frame or line not yet complete
  std::string out;  // reply bytes not yet sent
  std::int64_t frame_started_ns = 0;
  std::int64_t last_activity_ns = 0;
  bool skipping_line = false;  // ASCII: an overlong line was answered; drop it up to '\n'
  bool closed_by_peer = false;
  std::string close_reason;
  std::int32_t ascii_requests = 0;
  std::vector<RobotReply> grasps;  // of this connection's last LOOK
  std::size_t next = 0;
  std::int64_t sweep_taken_ns = 0;
};

void PoseServerOptions::Check() const {
  if (max_clients == 0 || max_clients > 1024) {
    throw OptionError("PoseServerOptions.max_clients must be in [1, 1024]");
  }
  if (!(frame_timeout_ms > 0.0) || !std::isfinite(frame_timeout_ms)) {
    throw OptionError("PoseServerOptions.frame_timeout_ms must be finite and > 0");
  }
  if (!(idle_timeout_ms >= 0.0) || !std::isfinite(idle_timeout_ms)) {
    throw OptionError("PoseServerOptions.idle_timeout_ms must be finite and >= 0 (0 = never)");
  }
  if (send_buffer_bytes < 0) throw OptionError("PoseServerOptions.send_buffer_bytes must be >= 0");
  if (max_pending_reply_bytes < kRobotReplyBytes) {
    throw OptionError("PoseServerOptions.max_pending_reply_bytes must hold one reply (>= 64)");
  }
}

std::string PoseServerCounters::Summary() const {
  return std::to_string(connections) + " connections (" + std::to_string(refused) + " refused), " +
         std::to_string(requests) + " requests, " + std::to_string(looks) + " LOOKs, " +
         std::to_string(bad_requests) + " bad requests; closed: " + std::to_string(frame_timeouts) +
         " frame timeouts, " + std::to_string(idle_timeouts) + " idle, " +
         std::to_string(slow_readers) + " slow readers, " + std::to_string(disconnects) +
         " by the client";
}

LookHandler JobLookHandler(JobRunner& runner,
                           std::shared_ptr<triangulation::ProfileSource> source) {
  return [&runner, source](const RobotRequest&) {
    LookOutcome out;
    std::shared_ptr<triangulation::ProfileSource> from = source;
    if (!from) from = std::make_shared<triangulation::FileProfileSource>(runner.job().profiles);
    try {
      std::optional<triangulation::ProfileSet> sweep = from->NextSweep();
      out.sweep_taken_ns = SteadyNowNs();
      if (!sweep) {
        out.status = ReplyStatus::kNoSweep;
        out.message = from->Describe() + " delivered no sweep";
        return out;
      }
      const JobResult result = runner.Run(*sweep, from->Describe());
      out.message = result.Summary();
      const std::vector<JobPart>& parts = runner.job().parts;
      for (const PartInstance& inst : result.parts.instances) {
        if (!inst.graspable) continue;
        const auto part = std::find_if(parts.begin(), parts.end(),
                                       [&](const JobPart& p) { return p.part.name == inst.part; });
        const auto k = inst.frame.rfind('_');
        for (const GraspPose& grasp : inst.grasps) {
          RobotReply reply;
          reply.status = ReplyStatus::kOk;
          reply.part = inst.part;
          reply.part_index = part == parts.end() ? -1 : static_cast<int>(part - parts.begin());
          reply.instance = k == std::string::npos ? 1 : std::atoi(inst.frame.c_str() + k + 1);
          reply.target_from_grasp = grasp.target_from_grasp;
          reply.position_sigma_mm = grasp.position_sigma_mm;
          out.grasps.push_back(reply);
        }
      }
      out.status = out.grasps.empty() ? ReplyStatus::kNoPart : ReplyStatus::kOk;
    } catch (const Error& e) {
      out.status = ReplyStatus::kFailed;
      out.message = e.what();
    }
    return out;
  };
}

PoseServer::PoseServer(LookHandler look, const PoseServerOptions& options)
    : look_(std::move(look)), options_(options) {
  options_.Check();
  const std::string where = options_.bind_address + ":" + std::to_string(options_.port);
  sockaddr_in addr = net::ListenAddress(options_.bind_address, options_.port, "TCP listen address");
  listen_fd_ = socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw InputError("cannot open a TCP socket for " + where);
  const int on = 1;
  setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
      listen(listen_fd_, 16) != 0) {
    const std::string message = std::string("cannot listen on TCP ") + where + ": " +
                                std::strerror(errno) +
                                "; choose another port or stop the program that holds it";
    close(listen_fd_);
    throw InputError(message);
  }
  socklen_t len = sizeof addr;
  getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  port_ = ntohs(addr.sin_port);
}

PoseServer::~PoseServer() {
  for (auto& c : clients_) close(c->fd);
  if (listen_fd_ >= 0) close(listen_fd_);
}

std::size_t PoseServer::clients() const {
  const std::lock_guard<std::mutex> lock(published_mutex_);
  return published_clients_;
}

PoseServerCounters PoseServer::counters() const {
  const std::lock_guard<std::mutex> lock(published_mutex_);
  return published_counters_;
}

void PoseServer::Publish() {
  const std::lock_guard<std::mutex> lock(published_mutex_);
  published_counters_ = counters_;
  published_clients_ = clients_.size();
}

void PoseServer::Serve(const std::atomic<bool>& stop) {
  while (!stop) Poll(50);
}

void PoseServer::Accept() {
  for (int round = 0; round < 64; ++round) {
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    const int fd =
        accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;
    char host[INET_ADDRSTRLEN] = "?";
    inet_ntop(AF_INET, &addr.sin_addr, host, sizeof host);
    const std::string peer = std::string(host) + ":" + std::to_string(ntohs(addr.sin_port));
    if (clients_.size() >= options_.max_clients) ReapGone();
    if (clients_.size() >= options_.max_clients) {
      close(fd);
      ++counters_.refused;
      Log("refused " + peer + ": " + std::to_string(options_.max_clients) + " clients connected");
      continue;
    }
    const int on = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on);
    if (options_.send_buffer_bytes > 0) {
      setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &options_.send_buffer_bytes,
                 sizeof options_.send_buffer_bytes);
    }
    auto client = std::make_unique<Client>();
    client->fd = fd;
    client->peer = peer;
    client->last_activity_ns = SteadyNowNs();
    clients_.push_back(std::move(client));
    ++counters_.connections;
    Log("connected " + peer);
  }
}

void PoseServer::Flush(Client& client) {
  while (!client.out.empty()) {
    const ssize_t n = send(client.fd, client.out.data(), client.out.size(), MSG_NOSIGNAL);
    if (n > 0) {
      client.out.erase(0, static_cast<std::size_t>(n));
    } else if (n < 0 && errno == EINTR) {
      continue;
    } else {
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) client.closed_by_peer = true;
      break;
    }
  }
  if (client.out.size() > options_.max_pending_reply_bytes && client.close_reason.empty()) {
    client.close_reason = "slow reader";
  }
}

void PoseServer::Reply(Client& client, RobotReply reply) {
  client.out +=
      client.mode == Client::Mode::kBinary ? EncodeBinaryReply(reply) : EncodeAsciiReply(reply);
  Flush(client);
}

void PoseServer::Handle(Client& client, const RobotRequest& request) {
  ++counters_.requests;
  RobotReply reply;
  reply.request_id = request.request_id;
  switch (request.command) {
    case RobotCommand::kPing:
      reply.status = ReplyStatus::kAlive;
      return Reply(client, reply);
    case RobotCommand::kLook: {
      ++counters_.looks;
      LookOutcome outcome;
      try {
        outcome = look_(request);
      } catch (const std::exception& e) {
        outcome.status = ReplyStatus::kFailed;
        outcome.message = e.what();
      }
      client.grasps = std::move(outcome.grasps);
      client.next = 0;
      client.sweep_taken_ns = outcome.sweep_taken_ns;
      Log("LOOK from " + client.peer + ": " + ReplyStatusName(outcome.status) + ", " +
          outcome.message);
      if (client.grasps.empty()) {
        reply.status = outcome.status == ReplyStatus::kOk ? ReplyStatus::kNoPart : outcome.status;
        if (client.sweep_taken_ns > 0)
          reply.latency_ms = (SteadyNowNs() - client.sweep_taken_ns) * 1e-6;
        return Reply(client, reply);
      }
      [[fallthrough]];
    }
    case RobotCommand::kNext:
      if (client.next >= client.grasps.size()) {
        reply.status = ReplyStatus::kNoMore;
        return Reply(client, reply);
      }
      reply = client.grasps[client.next++];
      reply.request_id = request.request_id;
      reply.instances_left = static_cast<std::int32_t>(client.grasps.size() - client.next);
      reply.latency_ms = (SteadyNowNs() - client.sweep_taken_ns) * 1e-6;
      return Reply(client, reply);
  }
}

void PoseServer::Read(Client& client, std::int64_t now_ns) {
  char buffer[kReadChunk];
  std::size_t total = 0;
  while (total < kMaxReadPerTurn && client.close_reason.empty()) {
    const ssize_t n = recv(client.fd, buffer, sizeof buffer, 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) {
      client.closed_by_peer = true;
      return;
    }
    if (n < 0) return;
    total += static_cast<std::size_t>(n);
    client.last_activity_ns = now_ns;
    if (client.in.empty()) client.frame_started_ns = now_ns;
    client.in.append(buffer, static_cast<std::size_t>(n));
    const std::size_t before = client.in.size();
    if (client.mode == Client::Mode::kUnknown) {
      if (client.in.size() < 2) continue;
      // "LC" opens a binary frame (magic "LCRQ"); requests as text start LOOK, NEXT or PING.
      client.mode =
          client.in.compare(0, 2, "LC") == 0 ? Client::Mode::kBinary : Client::Mode::kAscii;
    }
    const auto bad = [&](const std::string& why) {
      ++counters_.bad_requests;
      Log("bad request from " + client.peer + ": " + why);
      RobotReply reply;
      reply.status = ReplyStatus::kBadRequest;
      Reply(client, reply);
    };
    if (client.mode == Client::Mode::kBinary) {
      std::size_t used = 0;
      for (; client.in.size() - used >= kRobotRequestBytes; used += kRobotRequestBytes) {
        const RobotDecode d =
            DecodeBinaryRequest(std::string_view(client.in).substr(used, kRobotRequestBytes));
        d.request ? Handle(client, *d.request) : bad(d.error);
      }
      client.in.erase(0, used);
    } else {
      std::size_t start = 0;
      for (auto end = client.in.find('\n'); end != std::string::npos;
           end = client.in.find('\n', start)) {
        const std::string_view line = std::string_view(client.in).substr(start, end - start);
        start = end + 1;
        if (client.skipping_line) {
          client.skipping_line = false;
          continue;
        }
        RobotDecode d = DecodeAsciiRequest(line);
        if (d.request) {
          d.request->request_id = ++client.ascii_requests;
          Handle(client, *d.request);
        } else {
          bad(d.error);
        }
      }
      client.in.erase(0, start);
      if (client.in.size() >= kRobotMaxLineBytes) {
        if (!client.skipping_line) bad("line longer than 200 bytes");
        client.skipping_line = true;
        client.in.clear();
      }
    }
    if (!client.in.empty() && client.in.size() < before) {
      client.frame_started_ns = now_ns;  // a frame completed: what is left began in this read
    }
  }
}

void PoseServer::ReapGone() {
  std::vector<pollfd> fds;
  fds.reserve(clients_.size());
  for (const auto& c : clients_) fds.push_back({c->fd, static_cast<short>(POLLIN | POLLRDHUP), 0});
  const bool any = poll(fds.data(), fds.size(), 0) > 0;
  const std::int64_t now = SteadyNowNs();
  for (std::size_t i = 0; any && i < fds.size(); ++i) {
    Client& c = *clients_[i];
    // Everything that arrived is read first (a frame's rest, a peer's last bytes and its end),
    // so no one is judged overdue or alive on stale bytes.
    if (!c.closed_by_peer && (fds[i].revents & (POLLIN | POLLRDHUP | POLLHUP | POLLERR))) {
      Read(c, now);
    }
  }
  for (std::size_t i = clients_.size(); i-- > 0;) CloseIfDone(i, now);
}

bool PoseServer::CloseIfDone(std::size_t index, std::int64_t now_ns) {
  Client& c = *clients_[index];
  if (c.close_reason == "slow reader") {
    ++counters_.slow_readers;
    Close(index,
          "it does not read its replies (" + std::to_string(c.out.size()) + " bytes unread)");
    return true;
  }
  if (c.closed_by_peer) {
    ++counters_.disconnects;
    Close(index, c.in.empty() ? "disconnected" : "disconnected mid-frame");
    return true;
  }
  const auto frame_ns = static_cast<std::int64_t>(options_.frame_timeout_ms * 1e6);
  if (!c.in.empty() && now_ns - c.frame_started_ns > frame_ns) {
    ++counters_.frame_timeouts;
    Close(index, "a frame did not complete within " +
                     std::to_string(static_cast<int>(options_.frame_timeout_ms)) + " ms");
    return true;
  }
  const auto idle_ns = static_cast<std::int64_t>(options_.idle_timeout_ms * 1e6);
  if (idle_ns > 0 && now_ns - c.last_activity_ns > idle_ns) {
    ++counters_.idle_timeouts;
    Close(index,
          "silent for " + std::to_string(static_cast<int>(options_.idle_timeout_ms)) + " ms");
    return true;
  }
  return false;
}

void PoseServer::Close(std::size_t index, const std::string& why) {
  Client& client = *clients_[index];
  Log("closed " + client.peer + ": " + why);
  close(client.fd);
  clients_.erase(clients_.begin() + static_cast<std::ptrdiff_t>(index));
}

void PoseServer::Poll(int timeout_ms) {
  std::vector<pollfd> fds;
  fds.reserve(clients_.size() + 1);
  fds.push_back({listen_fd_, POLLIN, 0});
  for (const auto& c : clients_) {
    fds.push_back({c->fd, static_cast<short>(POLLIN | (c->out.empty() ? 0 : POLLOUT)), 0});
  }
  // Wake in time for the nearest frame timeout.
  const std::int64_t frame_ns = static_cast<std::int64_t>(options_.frame_timeout_ms * 1e6);
  std::int64_t now = SteadyNowNs();
  for (const auto& c : clients_) {
    if (c->in.empty()) continue;
    const std::int64_t left_ms = (c->frame_started_ns + frame_ns - now) / 1000000 + 1;
    timeout_ms = static_cast<int>(std::clamp<std::int64_t>(left_ms, 0, timeout_ms));
  }
  if (poll(fds.data(), fds.size(), timeout_ms) < 0 && errno != EINTR) {
    throw InputError(std::string("pose server: poll failed: ") + std::strerror(errno));
  }
  now = SteadyNowNs();
  for (std::size_t i = 1; i < fds.size(); ++i) {
    Client& c = *clients_[i - 1];
    if (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) Read(c, now);
    if (fds[i].revents & POLLOUT) Flush(c);
  }
  // After the reads (Accept may close clients that are done, which renumbers them).
  if (fds[0].revents & POLLIN) Accept();
  // `now` from before the reads: bytes that arrived while this round ran (a LOOK may take long)
  // get read in the next one before their frame is judged.
  for (std::size_t i = clients_.size(); i-- > 0;) CloseIfDone(i, now);
  Publish();
}

}  // namespace lasercell::localize
