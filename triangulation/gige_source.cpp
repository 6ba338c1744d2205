#include "triangulation/gige_source.hpp"

#include <arv.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/steady_time.hpp"

namespace lasercell::triangulation {

namespace {

constexpr std::int64_t kPollNs = 50'000'000;  // how often a waiting NextSweep looks at Stop()

// Takes ownership of a GError and throws it as an InputError about `what`.
void ThrowIfError(GError* error, const std::string& what) {
  if (error == nullptr) return;
  const std::string message = error->message != nullptr ? error->message : "unknown error";
  g_error_free(error);
  throw InputError(what + ": " + message);
}

bool HasFeature(ArvCamera* camera, const char* name) {
  GError* error = nullptr;
  const bool available = arv_camera_is_feature_available(camera, name, &error) != 0;
  if (error != nullptr) {
    g_error_free(error);
    return false;
  }
  return available;
}

std::int64_t GetInteger(ArvCamera* camera, const char* name, const std::string& what) {
  GError* error = nullptr;
  const gint64 value = arv_camera_get_integer(camera, name, &error);
  ThrowIfError(error, what + ": reading " + name);
  return value;
}

double GetFloat(ArvCamera* camera, const char* name, const std::string& what) {
  GError* error = nullptr;
  const double value = arv_camera_get_float(camera, name, &error);
  ThrowIfError(error, what + ": reading " + name);
  return value;
}

// The first of two features the device has, as an integer; 0 when it has neither.
std::uint32_t FirstInteger(ArvCamera* camera, const char* a, const char* b,
                           const std::string& what) {
  if (HasFeature(camera, a)) return static_cast<std::uint32_t>(GetInteger(camera, a, what));
  if (HasFeature(camera, b)) return static_cast<std::uint32_t>(GetInteger(camera, b, what));
  return 0;
}

std::string Text(const char* s) { return s != nullptr ? s : ""; }

std::uint64_t Info(ArvStream* stream, const char* name) {
  return arv_stream_get_info_uint64_by_name(stream, name);
}

}  // namespace

void GigeSourceOptions::Check() const {
  if (device.empty()) {
    throw OptionError("gige: device is empty; give the device's IPv4 address or Aravis id");
  }
  line_scan.Check();
  if (buffers < 2) throw OptionError("gige: buffers must be >= 2");
  if (socket_buffer_bytes < 65536) throw OptionError("gige: socket_buffer_bytes must be >= 65536");
  if (packet_size != 0 && (packet_size < 576 || packet_size > 65500)) {
    throw OptionError("gige: packet_size must be 0 (keep) or 576..65500 bytes, got " +
                      std::to_string(packet_size));
  }
  const auto positive = [](double v, const char* name) {
    if (!(std::isfinite(v) && v > 0.0)) {
      throw OptionError(std::string("gige: ") + name + " must be > 0 ms");
    }
  };
  positive(packet_timeout_ms, "packet_timeout_ms");
  positive(frame_retention_ms, "frame_retention_ms");
  positive(sweep_gap_ms, "sweep_gap_ms");
  if (!(std::isfinite(idle_timeout_ms) && idle_timeout_ms >= 0.0)) {
    throw OptionError("gige: idle_timeout_ms must be >= 0 (0 = wait for ever)");
  }
  if (frame_retention_ms <= packet_timeout_ms) {
    throw OptionError(
        "gige: frame_retention_ms must exceed packet_timeout_ms, or no resend "
        "can arrive before a buffer is given up");
  }
}

std::string GigeStreamCounters::Summary() const {
  return std::to_string(completed_buffers) + " buffers complete, " + std::to_string(failures) +
         " failed (" + std::to_string(timeouts) + " timed out), " + std::to_string(missing_frames) +
         " frames missing, " + std::to_string(underruns) +
         " underruns; packets: " + std::to_string(received_packets) + " received, " +
         std::to_string(missing_packets) + " missing, " + std::to_string(resend_requests) +
         " asked again, " + std::to_string(resent_packets) + " resent, " +
         std::to_string(duplicated_packets) + " duplicated, " + std::to_string(error_packets) +
         " errors, " + std::to_string(ignored_packets) + " ignored";
}

nlohmann::json GigeStreamCountersJson(const GigeStreamCounters& c) {
  return {{"completed_buffers", c.completed_buffers},
          {"failures", c.failures},
          {"underruns", c.underruns},
          {"timeouts", c.timeouts},
          {"missing_frames", c.missing_frames},
          {"received_packets", c.received_packets},
          {"missing_packets", c.missing_packets},
          {"error_packets", c.error_packets},
          {"ignored_packets", c.ignored_packets},
          {"resend_requests", c.resend_requests},
          {"resent_packets", c.resent_packets},
          {"duplicated_packets", c.duplicated_packets},
          {"transferred_bytes", c.transferred_bytes}};
}

struct GigeProfileSource::Device {
  ArvCamera* camera = nullptr;
  ArvStream* stream = nullptr;
  bool acquiring = false;
  ProfileHeader header;
  std::uint32_t lines = 0;
  std::string vendor, model, serial;  // read once: each is a GVCP round trip
  std::string description;

  ~Device() {
    if (acquiring) arv_camera_stop_acquisition(camera, nullptr);
    if (stream != nullptr) g_object_unref(stream);  // joins Aravis's stream thread
    if (camera != nullptr) g_object_unref(camera);
  }

  void Open(const GigeSourceOptions& o, LineScanOptions* line_scan);
  void Configure(const GigeSourceOptions& o, const std::string& what);
  void ReadGeometry(const GigeSourceOptions& o, LineScanOptions* line_scan,
                    const std::string& what);
  void StartStream(const GigeSourceOptions& o, const std::string& what);
};

void GigeProfileSource::Device::Open(const GigeSourceOptions& o, LineScanOptions* line_scan) {
  const std::string what = "gige device " + o.device;
  GError* error = nullptr;
  camera = arv_camera_new(o.device.c_str(), &error);
  if (camera == nullptr || error != nullptr) {
    ThrowIfError(error, what + " (is it on and reachable? `arv-tool-0.8` lists devices)");
    throw InputError(what + ": not found");
  }
  ArvDevice* device = arv_camera_get_device(camera);
  if (!ARV_IS_GV_DEVICE(device)) {
    throw InputError(what + ": not a GigE Vision device");
  }
  // Aravis's packet-socket path needs CAP_NET_RAW and bypasses the UDP stack; the socket path
  // works for every user and on loopback.
  arv_gv_device_set_stream_options(ARV_GV_DEVICE(device),
                                   ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
  vendor = Text(arv_camera_get_vendor_name(camera, nullptr));
  model = Text(arv_camera_get_model_name(camera, nullptr));
  serial = Text(arv_camera_get_device_serial_number(camera, nullptr));
  description = "gige " + o.device + " (" + vendor + " " + model + " " + serial + ")";
  Configure(o, what);
  ReadGeometry(o, line_scan, what);
  StartStream(o, what);
}

void GigeProfileSource::Device::Configure(const GigeSourceOptions& o, const std::string& what) {
  GError* error = nullptr;
  if (!o.pixel_format.empty()) {
    arv_camera_set_pixel_format_from_string(camera, o.pixel_format.c_str(), &error);
    ThrowIfError(error, what + ": setting PixelFormat to " + o.pixel_format);
  }
  if (o.lines_per_buffer != 0) {
    arv_camera_set_integer(camera, "Height", o.lines_per_buffer, &error);
    ThrowIfError(error, what + ": setting Height (lines per buffer) to " +
                            std::to_string(o.lines_per_buffer));
  }
  if (o.packet_size != 0) {
    arv_camera_gv_set_packet_size(camera, static_cast<gint>(o.packet_size), &error);
    ThrowIfError(error, what + ": setting the packet size to " + std::to_string(o.packet_size));
  }
  arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  ThrowIfError(error, what + ": setting AcquisitionMode to Continuous");
}

void GigeProfileSource::Device::ReadGeometry(const GigeSourceOptions& o, LineScanOptions* line_scan,
                                             const std::string& what) {
  header.columns = static_cast<std::uint32_t>(GetInteger(camera, "Width", what));
  lines = static_cast<std::uint32_t>(GetInteger(camera, "Height", what));
  header.first_column = HasFeature(camera, "OffsetX")
                            ? static_cast<std::uint32_t>(GetInteger(camera, "OffsetX", what))
                            : 0;
  header.image_width =
      o.image_width != 0 ? o.image_width : FirstInteger(camera, "SensorWidth", "WidthMax", what);
  header.image_height = o.image_height != 0
                            ? o.image_height
                            : FirstInteger(camera, "SensorHeight", "HeightMax", what);
  if (header.image_width == 0) header.image_width = header.first_column + header.columns;
  if (header.image_height == 0) {
    throw InputError(what + ": it has no SensorHeight or HeightMax; set image_height (rows)");
  }
  if (o.use_device_scale && HasFeature(camera, "Scan3dCoordinateScale")) {
    line_scan->row_scale_px = GetFloat(camera, "Scan3dCoordinateScale", what);
    if (HasFeature(camera, "Scan3dCoordinateOffset")) {
      line_scan->row_offset_px = GetFloat(camera, "Scan3dCoordinateOffset", what);
    }
  }
  if (line_scan->line_rate_hz == 0.0 && line_scan->line_timestamp_chunk_id == 0) {
    if (!HasFeature(camera, "AcquisitionLineRate")) {
      throw InputError(what +
                       ": its lines cannot be timed: it has no AcquisitionLineRate; set "
                       "line_rate_hz or the line-timestamp chunk id");
    }
    line_scan->line_rate_hz = GetFloat(camera, "AcquisitionLineRate", what);
  }
  line_scan->Check();
  // By number: a device's GenICam file may lack an entry name for its 3D formats.
  GError* error = nullptr;
  const ArvPixelFormat format = arv_camera_get_pixel_format(camera, &error);
  ThrowIfError(error, what + ": reading PixelFormat");
  const std::string format_name = PixelFormatName(format);
  header.metadata = "source: gige\ndevice: \"" + o.device + "\"\nvendor: \"" + vendor +
                    "\"\nmodel: \"" + model + "\"\nserial: \"" + serial + "\"\npixel_format: \"" +
                    format_name + "\"\nlines_per_buffer: " + std::to_string(lines) +
                    "\nrow_scale_px: " + FormatDouble(line_scan->row_scale_px) +
                    "\nrow_offset_px: " + FormatDouble(line_scan->row_offset_px) +
                    "\nline_rate_hz: " + FormatDouble(line_scan->line_rate_hz) + "\n";
  header.Check(what);
}

void GigeProfileSource::Device::StartStream(const GigeSourceOptions& o, const std::string& what) {
  GError* error = nullptr;
  const guint payload = arv_camera_get_payload(camera, &error);
  ThrowIfError(error, what + ": reading PayloadSize");
  // A device reports PayloadSize with its chunks; room for the timestamp chunk guards against
  // one that does not.
  const std::size_t image_bytes = 2 * static_cast<std::size_t>(header.columns) * lines;
  const std::size_t chunk_bytes =
      o.line_scan.line_timestamp_chunk_id != 0 ? 8 * static_cast<std::size_t>(lines) + 64 : 0;
  const std::size_t buffer_bytes = std::max<std::size_t>(payload, image_bytes + chunk_bytes);
  stream = arv_camera_create_stream(camera, nullptr, nullptr, &error);
  if (stream == nullptr || error != nullptr) {
    ThrowIfError(error, what + ": opening the stream");
    throw InputError(what + ": opening the stream failed");
  }
  g_object_set(stream, "packet-timeout", static_cast<guint>(o.packet_timeout_ms * 1000.0),
               "frame-retention", static_cast<guint>(o.frame_retention_ms * 1000.0),
               "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_FIXED, "socket-buffer-size",
               o.socket_buffer_bytes, nullptr);
  for (std::size_t i = 0; i < o.buffers; ++i) {
    arv_stream_push_buffer(stream, arv_buffer_new_allocate(buffer_bytes));
  }
  arv_camera_start_acquisition(camera, &error);
  ThrowIfError(error, what + ": starting acquisition");
  acquiring = true;
}

GigeProfileSource::GigeProfileSource(const GigeSourceOptions& options) : options_(options) {
  options_.Check();
  device_ = std::make_unique<Device>();
  device_->Open(options_, &options_.line_scan);
  assembler_ =
      std::make_unique<LineScanAssembler>(device_->header, device_->lines, options_.line_scan);
}

GigeProfileSource::~GigeProfileSource() = default;

const ProfileHeader& GigeProfileSource::header() const { return device_->header; }

std::uint32_t GigeProfileSource::lines_per_buffer() const { return device_->lines; }

std::string GigeProfileSource::Describe() const { return device_->description; }

std::string GigeProfileSource::LastSweepLoss() const {
  if (!last_ || last_->Clean()) return "";
  return last_->Summary();
}

GigeStreamCounters GigeProfileSource::counters() const {
  ArvStream* s = device_->stream;
  GigeStreamCounters c;
  c.completed_buffers = Info(s, "n_completed_buffers");
  c.failures = Info(s, "n_failures");
  c.underruns = Info(s, "n_underruns");
  c.timeouts = Info(s, "n_timeouts");
  c.missing_frames = Info(s, "n_missing_frames");
  c.received_packets = Info(s, "n_received_packets");
  c.missing_packets = Info(s, "n_missing_packets");
  c.error_packets = Info(s, "n_error_packets");
  c.ignored_packets = Info(s, "n_ignored_packets");
  c.resend_requests = Info(s, "n_resend_requests");
  c.resent_packets = Info(s, "n_resent_packets");
  c.duplicated_packets = Info(s, "n_duplicated_packets");
  c.transferred_bytes = Info(s, "n_transferred_bytes");
  return c;
}

namespace {

// One buffer from Aravis into the assembler; returns a sweep that reached its size limit.
std::optional<LineScanSweep> Take(ArvBuffer* buffer, const LineScanOptions& options,
                                  LineScanAssembler& assembler) {
  const guint64 frame_id = arv_buffer_get_frame_id(buffer);
  const ArvBufferPayloadType type = arv_buffer_get_payload_type(buffer);
  if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS) {
    assembler.AddIncomplete(frame_id);
    return std::nullopt;
  }
  LineScanBuffer b;
  b.frame_id = frame_id;
  if (type == ARV_BUFFER_PAYLOAD_TYPE_IMAGE ||
      type == ARV_BUFFER_PAYLOAD_TYPE_EXTENDED_CHUNK_DATA) {
    size_t size = 0;
    const void* data = arv_buffer_get_data(buffer, &size);
    b.timestamp_ns = static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer));
    b.pixel_format = arv_buffer_get_image_pixel_format(buffer);
    b.width = static_cast<std::uint32_t>(std::max(0, arv_buffer_get_image_width(buffer)));
    b.height = static_cast<std::uint32_t>(std::max(0, arv_buffer_get_image_height(buffer)));
    b.x_offset = static_cast<std::uint32_t>(std::max(0, arv_buffer_get_image_x(buffer)));
    b.image = std::string_view(static_cast<const char*>(data), data != nullptr ? size : 0);
    if (options.line_timestamp_chunk_id != 0 && arv_buffer_has_chunks(buffer)) {
      size_t chunk_size = 0;
      const void* chunk =
          arv_buffer_get_chunk_data(buffer, options.line_timestamp_chunk_id, &chunk_size);
      if (chunk != nullptr) b.line_timestamps = {static_cast<const char*>(chunk), chunk_size};
    }
  }  // any other payload (pixel_format 0) is refused by the assembler
  return assembler.AddComplete(b);
}

}  // namespace

std::optional<LineScanSweep> GigeProfileSource::NextLineScanSweep() {
  const std::int64_t gap_ns = static_cast<std::int64_t>(options_.sweep_gap_ms * 1e6);
  const std::int64_t idle_ns = static_cast<std::int64_t>(options_.idle_timeout_ms * 1e6);
  std::int64_t last_activity = SteadyNowNs();
  while (!stop_) {
    const std::int64_t now = SteadyNowNs();
    if (assembler_->open() && now - last_activity >= gap_ns) {
      LineScanSweep sweep = *assembler_->Finish(LineScanEnd::kGap);
      last_ = sweep.account;
      return sweep;
    }
    if (!assembler_->open() && idle_ns > 0 && now - last_activity >= idle_ns) return std::nullopt;
    std::int64_t wait_ns = kPollNs;
    if (assembler_->open()) wait_ns = std::min(wait_ns, last_activity + gap_ns - now);
    ArvBuffer* buffer =
        arv_stream_timeout_pop_buffer(device_->stream, static_cast<guint64>(wait_ns / 1000 + 1));
    if (buffer == nullptr) continue;
    last_activity = SteadyNowNs();
    std::optional<LineScanSweep> full = Take(buffer, options_.line_scan, *assembler_);
    // Aravis sets a buffer's block id from its leader; a reused buffer whose leader is lost
    // must not report the previous frame's id.
    arv_buffer_set_frame_id(buffer, 0);
    arv_stream_push_buffer(device_->stream, buffer);
    if (full) {
      last_ = full->account;
      return full;
    }
  }
  return std::nullopt;
}

std::optional<ProfileSet> GigeProfileSource::NextSweep() {
  std::optional<LineScanSweep> sweep = NextLineScanSweep();
  if (!sweep) return std::nullopt;
  return std::move(sweep->set);
}

}  // namespace lasercell::triangulation
