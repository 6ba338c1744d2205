// `lasercell bench stream`: the UDP profile receiver on loopback (triangulation/udp_stream.hpp).
// A sender thread replays sweeps at a given profile rate (default 10x the paper's sensor peak,
// 3900 profiles/s x 1024 columns) while the receiver reassembles them; reported per datagram
// size: delivered profile rate, profiles lost, OS drops, the most profiles held in
// reassembly, peak resident memory; and, through seeded impairments (1 % loss, reorder,
// duplication), whether each sweep's loss account equals what the sender dropped.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "core/json_io.hpp"
#include "tools/bench.hpp"
#include "triangulation/udp_stream.hpp"

namespace lasercell::tools {
namespace {

struct StreamBenchArgs {
  int sweeps = 40;               ///< Sweeps per run.
  int sweep_profiles = 1000;     ///< Profiles per sweep.
  std::uint32_t columns = 1024;  ///< Columns per profile.
  double rate_hz = 39000.0;      ///< Profiles per second (10 x 3900).
  std::vector<std::size_t> datagram_bytes = {1472, 8972};
  double impaired = 0.01;  ///< Loss = reorder = duplicate probability of the second pass.
  std::string json_out;
};

triangulation::ProfileSet BenchSweep(const StreamBenchArgs& args, std::uint64_t first) {
  triangulation::ProfileSet set;
  set.header.columns = args.columns;
  set.header.image_width = args.columns;
  set.header.joint_count = 6;
  set.header.robot = "vision_robot";
  std::mt19937 rng(static_cast<unsigned>(first));
  std::uniform_real_distribution<float> row(100.0f, 900.0f);
  for (int i = 0; i < args.sweep_profiles; ++i) {
    triangulation::Profile p = triangulation::Profile::Empty(args.columns, 6);
    p.sequence = first + static_cast<std::uint64_t>(i);
    p.timestamp_ns = static_cast<std::int64_t>(p.sequence * 1e9 / 3900.0);
    for (int j = 0; j < 6; ++j) p.joints_rad[j] = 0.001 * i + j;
    for (std::uint32_t c = 0; c < args.columns; ++c) {
      p.row_px[c] = row(rng);
      p.intensity[c] = 0.7f;
      p.width_px[c] = 2.5f;
    }
    set.profiles.push_back(std::move(p));
  }
  return set;
}

// Reassembly alone, without sockets: every datagram of `sweeps` sweeps fed to one
// SweepAssembler on this thread; profiles per second.
double ReassemblyRate(const StreamBenchArgs& args, std::size_t datagram_bytes) {
  std::vector<triangulation::SweepDatagrams> encoded;
  for (int k = 0; k < args.sweeps; ++k) {
    triangulation::DatagramOptions options;
    options.max_datagram_bytes = datagram_bytes;
    options.sweep_id = static_cast<std::uint32_t>(k);
    encoded.push_back(triangulation::EncodeSweepDatagrams(
        BenchSweep(args, static_cast<std::uint64_t>(k) * args.sweep_profiles), options));
  }
  triangulation::SweepAssembler assembler;
  std::size_t delivered = 0;
  const auto start = std::chrono::steady_clock::now();
  for (const auto& sweep : encoded) {
    for (const std::string& d : sweep.datagrams) assembler.Feed(d, 0);
    while (auto done = assembler.TakeFinished(0)) delivered += done->account.delivered;
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (delivered != encoded.size() * static_cast<std::size_t>(args.sweep_profiles)) {
    throw InternalError("bench stream: reassembly lost profiles without impairments");
  }
  return static_cast<double>(delivered) / seconds;
}

struct PassResult {
  std::size_t datagram_bytes = 0;
  double impaired = 0.0;
  std::size_t sent_profiles = 0, delivered = 0, lost = 0, kernel_dropped = 0;
  std::size_t peak_reassembly = 0, accounts_exact = 0, sweeps = 0;
  double seconds = 0.0, send_seconds = 0.0, profiles_per_s = 0.0, megabytes_per_s = 0.0;
};

// One pass: the sender thread sends every sweep; the receiver takes them as they end.
PassResult RunPass(const StreamBenchArgs& args, std::size_t datagram_bytes, double impaired) {
  triangulation::UdpSourceOptions source_options;
  source_options.bind_address = "127.0.0.1";
  source_options.idle_timeout_ms = 2000;
  triangulation::UdpProfileSource source(source_options);
  // Encoded before the clock starts, so the sender thread only paces and sends.
  struct Encoded {
    triangulation::SweepDatagrams datagrams;
    triangulation::ImpairedOrder order;
    triangulation::SentAccount account;
  };
  std::vector<Encoded> sweeps(static_cast<std::size_t>(args.sweeps));
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    const triangulation::ProfileSet set =
        BenchSweep(args, static_cast<std::uint64_t>(k) * args.sweep_profiles);
    triangulation::DatagramOptions datagram;
    datagram.max_datagram_bytes = datagram_bytes;
    datagram.sweep_id = static_cast<std::uint32_t>(k);
    triangulation::Impairments impairments;
    impairments.loss = impairments.reorder = impairments.duplicate = impaired;
    impairments.seed = 100 + k;
    sweeps[k].datagrams = triangulation::EncodeSweepDatagrams(set, datagram);
    sweeps[k].order =
        triangulation::ImpairDatagrams(sweeps[k].datagrams.datagrams.size(), impairments);
    sweeps[k].account = triangulation::AccountSent(set, sweeps[k].datagrams, sweeps[k].order);
  }
  const auto start = std::chrono::steady_clock::now();
  double send_seconds = 0.0;
  std::thread sender([&] {
    triangulation::UdpSender udp("127.0.0.1:" + std::to_string(source.port()));
    for (const Encoded& e : sweeps) {
      triangulation::SendDatagrams(udp, e.datagrams, e.order, args.rate_hz);
    }
    send_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  });
  std::vector<triangulation::SweepAccount> got;
  while (got.size() < sweeps.size()) {
    auto sweep = source.NextAssembledSweep();
    if (!sweep) break;
    got.push_back(sweep->account);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  sender.join();
  PassResult r;
  r.datagram_bytes = datagram_bytes;
  r.impaired = impaired;
  r.sweeps = got.size();
  r.seconds = seconds;
  r.sent_profiles = sweeps.size() * static_cast<std::size_t>(args.sweep_profiles);
  r.send_seconds = send_seconds;
  for (const triangulation::SweepAccount& a : got) {
    r.delivered += a.delivered;
    if (a.sweep_id >= sweeps.size()) continue;
    const triangulation::SentAccount& s = sweeps[a.sweep_id].account;
    std::vector<std::uint64_t> missing;
    for (const auto& range : a.missing) {
      for (std::uint64_t q = range.first; q <= range.last; ++q) missing.push_back(q);
    }
    // A lost tail is announced only by END; without END it cannot be known.
    std::vector<std::uint64_t> expected = s.lost_profiles;
    if (s.end_dropped)
      std::erase_if(expected, [&](std::uint64_t q) { return q > a.last_sequence; });
    r.accounts_exact += missing == expected && a.incomplete == s.partial_profiles ? 1 : 0;
  }
  r.lost = r.sent_profiles - r.delivered;
  r.kernel_dropped = source.counters().kernel_dropped;
  r.peak_reassembly = source.counters().peak_reassembly;
  // The rate the receiver kept up with: every profile sent, over the time until the last sweep
  // was delivered (it cannot be faster than the sender's pace).
  r.profiles_per_s = static_cast<double>(r.sent_profiles) / seconds;
  r.megabytes_per_s = r.profiles_per_s * (16 + 48 + 12.0 * args.columns) / 1e6;
  return r;
}

void RunStreamBench(const StreamBenchArgs& args) {
  if (args.sweeps < 1 || args.sweep_profiles < 1 || args.columns < 1 || !(args.rate_hz >= 0)) {
    throw OptionError("bench stream: --sweeps, --sweep-profiles and --columns must be >= 1");
  }
  std::printf(
      "UDP profile stream on loopback: %d sweeps x %d profiles x %u columns, 6 joints, "
      "target %.0f profiles/s\n\n",
      args.sweeps, args.sweep_profiles, args.columns, args.rate_hz);
  std::printf(
      "| datagram bytes | impairments | profiles/s received | MB/s | lost profiles | OS drops "
      "| exact loss accounts | peak in reassembly |\n"
      "|---:|---|---:|---:|---:|---:|---:|---:|\n");
  nlohmann::json rows = nlohmann::json::array();
  for (const double impaired : {0.0, args.impaired}) {
    for (const std::size_t bytes : args.datagram_bytes) {
      const PassResult r = RunPass(args, bytes, impaired);
      const std::string label =
          impaired > 0
              ? std::to_string(static_cast<int>(impaired * 100 + 0.5)) + " % loss/reorder/dup"
              : "none";
      std::printf("| %zu | %s | %.0f | %.0f | %zu | %zu | %zu of %zu | %zu |\n", bytes,
                  label.c_str(), r.profiles_per_s, r.megabytes_per_s, r.lost, r.kernel_dropped,
                  r.accounts_exact, r.sweeps, r.peak_reassembly);
      std::fflush(stdout);
      rows.push_back({{"datagram_bytes", bytes},
                      {"impaired_probability", impaired},
                      {"sweeps", r.sweeps},
                      {"sent_profiles", r.sent_profiles},
                      {"delivered_profiles", r.delivered},
                      {"lost_profiles", r.lost},
                      {"kernel_dropped", r.kernel_dropped},
                      {"exact_loss_accounts", r.accounts_exact},
                      {"peak_reassembly", r.peak_reassembly},
                      {"seconds", r.seconds},
                      {"profiles_per_s", r.profiles_per_s},
                      {"megabytes_per_s", r.megabytes_per_s},
                      {"send_seconds", r.send_seconds}});
    }
  }
  nlohmann::json alone = nlohmann::json::array();
  std::printf(
      "\nReassembly alone (SweepAssembler, one thread, no sockets):\n\n"
      "| datagram bytes | profiles/s |\n|---:|---:|\n");
  for (const std::size_t bytes : args.datagram_bytes) {
    const double rate = ReassemblyRate(args, bytes);
    std::printf("| %zu | %.0f |\n", bytes, rate);
    alone.push_back({{"datagram_bytes", bytes}, {"profiles_per_s", rate}});
  }
  json::WriteFile(args.json_out, {{"benchmark", "stream"},
                                  {"reassembly_alone", alone},
                                  {"sweeps", args.sweeps},
                                  {"sweep_profiles", args.sweep_profiles},
                                  {"columns", args.columns},
                                  {"rate_hz", args.rate_hz},
                                  {"rows", rows}});
}

}  // namespace

void AddStreamBenchCommand(CLI::App& bench) {
  CLI::App* cmd = bench.add_subcommand(
      "stream", "UDP profile receiver on loopback: rate, loss, memory, loss-account exactness");
  auto args = std::make_shared<StreamBenchArgs>();
  cmd->add_option("--sweeps", args->sweeps, "Sweeps per pass")->capture_default_str();
  cmd->add_option("--sweep-profiles", args->sweep_profiles, "Profiles per sweep")
      ->capture_default_str();
  cmd->add_option("--columns", args->columns, "Columns per profile")->capture_default_str();
  cmd->add_option("--rate", args->rate_hz, "Profiles per second sent (0 = as fast as possible)")
      ->capture_default_str();
  cmd->add_option("--datagram-bytes", args->datagram_bytes, "Datagram sizes to measure")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--impaired", args->impaired,
                  "Loss = reorder = duplicate probability of the impaired passes")
      ->capture_default_str();
  cmd->add_option("--json", args->json_out, "Also write the rows as JSON");
  cmd->callback([args] { RunStreamBench(*args); });
}

}  // namespace lasercell::tools
