#pragma once
// The pose server for the handling robot (`lasercell serve`): robots connect over TCP and speak
// the robot protocol (robot_protocol.hpp, binary or ASCII, detected per connection). A LOOK
// takes the next sweep from the job's source, runs the job and answers with the first graspable
// grasp; NEXT gives the following ones of that connection's last LOOK; PING answers ALIVE.
//
// One thread, one poll loop: a LOOK runs to completion while other clients' bytes wait in the
// kernel. Nothing a client does stalls the others or grows memory beyond the options' bounds:
// a frame or line must complete within frame_timeout_ms (else the connection is closed), replies
// a client does not read beyond max_pending_reply_bytes close its connection, clients beyond
// max_clients are closed at once (clients whose peer has hung up, or whose frame or silence is
// overdue, are closed first, so they do not count). A client that left with requests still
// unsent in its kernel looks alive until they are read: set max_clients above the number of
// robots. Malformed requests are answered with BAD_REQUEST.

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "localize/job_run.hpp"
#include "localize/robot_protocol.hpp"
#include "triangulation/profile_source.hpp"

namespace lasercell::localize {

/// Options of PoseServer.
struct PoseServerOptions {
  std::string bind_address = "0.0.0.0";  ///< Interface to listen on.
  std::uint16_t port = 0;                ///< TCP port; 0 = any free port (see port()).
  std::size_t max_clients = 8;           ///< Connections served at once (above the robots').
  double frame_timeout_ms = 2000.0;      ///< A started frame or line must complete within this.
  /// A connection silent for this long is closed, ms; 0 = never (robots keep theirs open).
  double idle_timeout_ms = 0.0;
  std::size_t max_pending_reply_bytes = 64 * 1024;  ///< Unread replies that close a connection.
  /// Kernel send buffer per connection, bytes (0 = the system's default); replies beyond it
  /// wait in the server's own buffer, which max_pending_reply_bytes bounds.
  int send_buffer_bytes = 0;
  /// Throws OptionError naming the field.
  void Check() const;
};

/// What a LOOK produced.
struct LookOutcome {
  /// kOk with grasps, kNoPart without, kNoSweep when the source had none, kFailed on an error.
  ReplyStatus status = ReplyStatus::kNoPart;
  /// Graspable grasps in reply order (status, part, part_index, instance, pose, sigma set).
  std::vector<RobotReply> grasps;
  std::int64_t sweep_taken_ns = 0;  ///< Steady clock when the source delivered the sweep.
  std::string message;              ///< For the server's log.
};

/// Runs a LOOK: takes a sweep, localizes, returns the grasps.
using LookHandler = std::function<LookOutcome(const RobotRequest&)>;

/// A handler that runs `runner`'s job on the next sweep of `source`, or, when `source` is null,
/// on the job's profile file read again for every LOOK (replaying one capture).
LookHandler JobLookHandler(JobRunner& runner,
                           std::shared_ptr<triangulation::ProfileSource> source = nullptr);

/// Counters since the server started.
struct PoseServerCounters {
  std::uint64_t connections = 0;     ///< Accepted and served.
  std::uint64_t refused = 0;         ///< Closed at once: max_clients reached.
  std::uint64_t requests = 0;        ///< Well-formed requests.
  std::uint64_t looks = 0;           ///< LOOKs run.
  std::uint64_t bad_requests = 0;    ///< Answered BAD_REQUEST.
  std::uint64_t frame_timeouts = 0;  ///< Closed: a frame did not complete in time.
  std::uint64_t idle_timeouts = 0;   ///< Closed: silent for idle_timeout_ms.
  std::uint64_t slow_readers = 0;    ///< Closed: unread replies over the bound.
  std::uint64_t disconnects = 0;     ///< Closed by the client (mid-frame or not).
  std::string Summary() const;
};

/// A TCP server answering robots.
class PoseServer {
 public:
  /// Binds and listens. Throws InputError naming the address when it cannot.
  PoseServer(LookHandler look, const PoseServerOptions& options);
  ~PoseServer();
  PoseServer(const PoseServer&) = delete;
  PoseServer& operator=(const PoseServer&) = delete;

  /// Serves until `stop` becomes true (checked at least every 50 ms).
  void Serve(const std::atomic<bool>& stop);
  /// One turn of the loop: waits at most `timeout_ms` for activity and handles it.
  void Poll(int timeout_ms);
  /// The bound port.
  std::uint16_t port() const { return port_; }
  /// Connections open at the end of the last Poll. Safe to call from any thread, also while
  /// another thread serves.
  std::size_t clients() const;
  /// The counters at the end of the last Poll (a copy). Safe to call from any thread, also while
  /// another thread serves.
  PoseServerCounters counters() const;
  /// Where one-line events go (connections, LOOK outcomes, closed clients); default: nowhere.
  void SetLog(std::function<void(const std::string&)> log) { log_ = std::move(log); }

 private:
  struct Client;
  void Accept();
  /// Reads what every client has sent (a hung-up peer's last bytes and its end included), then
  /// closes every client that is done (CloseIfDone), so that connections already gone or overdue
  /// do not count against max_clients.
  void ReapGone();
  /// Closes client `index` when its peer hung up, it stopped reading its replies, its frame did
  /// not complete within frame_timeout_ms or it was silent past idle_timeout_ms; true then.
  bool CloseIfDone(std::size_t index, std::int64_t now_ns);
  void Read(Client& client, std::int64_t now_ns);
  void Handle(Client& client, const RobotRequest& request);
  void Reply(Client& client, RobotReply reply);
  void Flush(Client& client);
  void Close(std::size_t index, const std::string& why);
  /// Copies the counters and the client count for counters() and clients().
  void Publish();
  void Log(const std::string& line) const {
    if (log_) log_(line);
  }

  LookHandler look_;
  PoseServerOptions options_;
  int listen_fd_ = -1;
  std::uint16_t port_ = 0;
  std::vector<std::unique_ptr<Client>> clients_;
  PoseServerCounters counters_;  // the serving thread's own
  mutable std::mutex published_mutex_;
  PoseServerCounters published_counters_;
  std::size_t published_clients_ = 0;
  std::function<void(const std::string&)> log_;
};

}  // namespace lasercell::localize
