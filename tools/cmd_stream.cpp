// Profiles over UDP (triangulation/udp_stream.hpp):
//   `lasercell stream send FILE.lcp --to HOST:PORT [--rate HZ] [--loss P --reorder P
//    --duplicate P --seed N]` replays a profile file as a sensor would, through seeded
//    impairments for tests;
//   `lasercell scan record --udp PORT | --gige DEVICE --out FILE.lcp` writes the next sweep that
//    arrives over UDP or from a GigE Vision line profiler (triangulation/gige_source.hpp), and
//    its loss account.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "core/error.hpp"
#include "core/json_io.hpp"
#include "tools/commands.hpp"
#include "triangulation/gige_source.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/udp_stream.hpp"

namespace lasercell::tools {
namespace {

struct SendArgs {
  std::string file, to, account_json;
  triangulation::SendOptions options;
  int repeat = 1;
  bool quiet = false;
};

void RunSend(SendArgs& args) {
  if (args.repeat < 1) throw OptionError("--repeat must be >= 1");
  const triangulation::ProfileSet set = triangulation::ReadProfiles(args.file);
  triangulation::UdpSender sender(args.to);
  nlohmann::json sweeps = nlohmann::json::array();
  for (int k = 0; k < args.repeat; ++k) {
    triangulation::SendOptions options = args.options;
    options.datagram.sweep_id += static_cast<std::uint32_t>(k);
    options.impairments.seed += static_cast<std::uint64_t>(k);
    const triangulation::SentAccount account = triangulation::SendSweep(sender, set, options);
    nlohmann::json j = triangulation::SentAccountJson(account);
    j["sweep_id"] = options.datagram.sweep_id;
    sweeps.push_back(j);
    if (!args.quiet) {
      std::printf("sweep %u -> %s: %s\n", options.datagram.sweep_id, args.to.c_str(),
                  account.Summary().c_str());
    }
  }
  json::WriteFile(args.account_json,
                  {{"format", "lasercell.stream_sent"}, {"version", 1}, {"sweeps", sweeps}});
}

struct RecordArgs {
  std::string out, account_json;
  int udp_port = -1;
  triangulation::UdpSourceOptions options;
  triangulation::GigeSourceOptions gige;
  double timeout_s = 10.0;
  bool quiet = false;
};

// Writes the recorded sweep, and its account (lasercell.stream_received) with `account`'s
// source-specific fields, then prints the summaries.
void WriteRecorded(const RecordArgs& args, const triangulation::ProfileSet& set,
                   const std::string& source, nlohmann::json account, const std::string& summary,
                   const std::string& counters) {
  triangulation::WriteProfiles(args.out, set);
  account["format"] = "lasercell.stream_received";
  account["version"] = 1;
  account["source"] = source;
  json::WriteFile(args.account_json, account);
  if (!args.quiet) {
    std::printf("%s\n%s\nwrote %s\n", summary.c_str(), counters.c_str(), args.out.c_str());
  }
}

void RunRecordGige(RecordArgs& args) {
  args.gige.idle_timeout_ms = args.timeout_s * 1000.0;
  triangulation::GigeProfileSource source(args.gige);
  if (!args.quiet) std::printf("receiving from %s\n", source.Describe().c_str());
  std::fflush(stdout);
  auto sweep = source.NextLineScanSweep();
  if (!sweep) {
    throw InputError("no buffer arrived from " + source.Describe() + " within " +
                     std::to_string(args.timeout_s) + " s; is the sensor triggered?");
  }
  const triangulation::GigeStreamCounters counters = source.counters();
  WriteRecorded(args, sweep->set, source.Describe(),
                {{"line_scan", triangulation::LineScanAccountJson(sweep->account)},
                 {"gige_counters", triangulation::GigeStreamCountersJson(counters)}},
                sweep->account.Summary(), counters.Summary());
}

void RunRecord(RecordArgs& args) {
  if (!(args.timeout_s > 0.0)) throw OptionError("--timeout-s must be > 0");
  if ((args.udp_port >= 0) == !args.gige.device.empty()) {
    throw OptionError("give exactly one of --udp PORT and --gige DEVICE");
  }
  if (!args.gige.device.empty()) {
    RunRecordGige(args);
    return;
  }
  if (args.udp_port > 65535) throw OptionError("--udp must be a port in 0..65535");
  args.options.port = static_cast<std::uint16_t>(args.udp_port);
  args.options.idle_timeout_ms = args.timeout_s * 1000.0;
  triangulation::UdpProfileSource source(args.options);
  if (!args.quiet) std::printf("listening on %s\n", source.Describe().c_str());
  std::fflush(stdout);
  auto sweep = source.NextAssembledSweep();
  if (!sweep) {
    throw InputError("no sweep arrived on " + source.Describe() + " within " +
                     std::to_string(args.timeout_s) +
                     " s; check the sender's destination port and the firewall");
  }
  WriteRecorded(args, sweep->set, source.Describe(),
                {{"sweep", triangulation::SweepAccountJson(sweep->account)},
                 {"counters", triangulation::StreamCountersJson(source.counters())}},
                sweep->account.Summary(), source.counters().Summary());
}

}  // namespace

void AddStreamCommands(CLI::App& app) {
  CLI::App* stream = app.add_subcommand("stream", "Laser profiles over the network (UDP)");
  stream->require_subcommand(1);
  CLI::App* send = stream->add_subcommand(
      "send", "Replay a profile file (.lcp) over UDP at the sensor's rate, one sweep per repeat");
  auto s = std::make_shared<SendArgs>();
  send->add_option("file", s->file, "Laser profiles (.lcp)")->required();
  send->add_option("--to", s->to, "Receiver HOST:PORT, e.g. 127.0.0.1:5000")->required();
  send->add_option("--rate", s->options.rate_hz,
                   "Profiles per second (the paper's sensor peaks at 3900); 0 = as fast as "
                   "possible")
      ->capture_default_str();
  send->add_option("--sensor-id", s->options.datagram.sensor_id)->capture_default_str();
  send->add_option("--sweep-id", s->options.datagram.sweep_id,
                   "Number of the first sweep (each repeat adds 1)")
      ->capture_default_str();
  send->add_option("--datagram-bytes", s->options.datagram.max_datagram_bytes,
                   "Largest datagram payload (1472: Ethernet MTU, 8972: jumbo frames)")
      ->capture_default_str();
  send->add_option("--loss", s->options.impairments.loss, "Probability a datagram is dropped");
  send->add_option("--reorder", s->options.impairments.reorder,
                   "Probability a datagram is held back behind up to 8 others");
  send->add_option("--duplicate", s->options.impairments.duplicate,
                   "Probability a datagram is sent twice");
  send->add_option("--seed", s->options.impairments.seed, "Seed of the impairments")
      ->capture_default_str();
  send->add_option("--repeat", s->repeat, "Sweeps to send")->capture_default_str();
  send->add_option("--account-json", s->account_json,
                   "Write what was sent and dropped (lasercell.stream_sent)");
  send->add_flag("--quiet", s->quiet, "No summary lines");
  send->callback([s] { RunSend(*s); });
}

void AddScanRecordCommand(CLI::App& scan) {
  CLI::App* record = scan.add_subcommand(
      "record",
      "Receive the next sweep of profiles over UDP or from a GigE Vision sensor and write it "
      "(.lcp)");
  auto r = std::make_shared<RecordArgs>();
  record->add_option("--udp", r->udp_port, "UDP port to listen on");
  AddGigeOptions(record, &r->gige);
  record->add_option("--out", r->out, "Profile file to write (.lcp)")->required();
  record->add_option("--bind", r->options.bind_address, "Listen address")->capture_default_str();
  record
      ->add_option("--sensor-id", r->options.assembly.sensor_id,
                   "Only this sensor's datagrams (-1: any)")
      ->capture_default_str();
  record
      ->add_option("--timeout-s", r->timeout_s,
                   "Give up after this long without a datagram or buffer")
      ->capture_default_str();
  record->add_option("--account-json", r->account_json,
                     "Write the sweep's loss account and the stream counters "
                     "(lasercell.stream_received)");
  record->add_flag("--quiet", r->quiet, "No summary lines");
  record->callback([r] { RunRecord(*r); });
}

}  // namespace lasercell::tools
