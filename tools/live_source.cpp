// Live sweep sources on the command line: the options of a GigE Vision line-profiler source
// (triangulation/gige_source.hpp), shared by `scan record`, `job run` and `serve`, and the UDP or
// GigE source `job run` and `serve` take their sweeps from.
#include <CLI/CLI.hpp>

#include "core/error.hpp"
#include "tools/commands.hpp"
#include "triangulation/gige_source.hpp"
#include "triangulation/udp_stream.hpp"

namespace lasercell::tools {

void AddGigeOptions(CLI::App* app, triangulation::GigeSourceOptions* o) {
  app->add_option("--gige", o->device,
                  "Take sweeps from this GigE Vision line profiler: its IPv4 address or Aravis "
                  "device id (`arv-tool-0.8` lists them)");
  app->add_option("--lines-per-buffer", o->lines_per_buffer,
                  "With --gige: profiles per buffer, written to Height (0 = keep the device's)");
  app->add_option("--pixel-format", o->pixel_format,
                  "With --gige: written to PixelFormat, e.g. Coord3D_C16 (default: keep)");
  app->add_option("--packet-size", o->packet_size,
                  "With --gige: GVSP packet size in bytes (8972 with jumbo frames; 0 = keep)");
  app->add_option("--line-rate", o->line_scan.line_rate_hz,
                  "With --gige: profiles per second, to time lines without a timestamp chunk "
                  "(0 = the device's AcquisitionLineRate)");
  app->add_option("--line-timestamp-chunk", o->line_scan.line_timestamp_chunk_id,
                  "With --gige: chunk id holding one u64 ns timestamp per line (0 = none)");
  app->add_option("--row-scale", o->line_scan.row_scale_px,
                  "With --gige: peak row per count, px, when the device has no "
                  "Scan3dCoordinateScale")
      ->capture_default_str();
  app->add_option("--image-height", o->image_height,
                  "With --gige: sensor rows (0 = the device's SensorHeight)");
  app->add_option("--max-profiles", o->line_scan.max_sweep_profiles,
                  "With --gige: a sweep ends after this many profiles")
      ->capture_default_str();
  app->add_option("--sweep-gap-ms", o->sweep_gap_ms,
                  "With --gige: a sweep ends when no buffer arrives for this long")
      ->capture_default_str();
}

std::shared_ptr<triangulation::ProfileSource> MakeLiveSource(
    int udp_port, const std::string& udp_bind, const triangulation::GigeSourceOptions& gige,
    double wait_s, const std::string& wait_flag) {
  const bool udp = udp_port >= 0;
  if (!udp && gige.device.empty()) return nullptr;
  if (udp && !gige.device.empty()) throw OptionError("give at most one of --udp and --gige");
  if (!(wait_s > 0.0)) throw OptionError(wait_flag + " must be > 0");
  if (udp) {
    if (udp_port > 65535) throw OptionError("--udp must be a port in 0..65535");
    triangulation::UdpSourceOptions o;
    o.bind_address = udp_bind;
    o.port = static_cast<std::uint16_t>(udp_port);
    o.idle_timeout_ms = wait_s * 1000.0;
    return std::make_shared<triangulation::UdpProfileSource>(o);
  }
  triangulation::GigeSourceOptions o = gige;
  o.idle_timeout_ms = wait_s * 1000.0;
  return std::make_shared<triangulation::GigeProfileSource>(o);
}

}  // namespace lasercell::tools
