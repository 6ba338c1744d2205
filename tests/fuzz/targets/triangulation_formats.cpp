// Fuzz targets for what triangulation reads: `.lcp` profile files, UDP profile datagrams and
// their reassembly into sweeps, and GigE Vision line-scan buffers into sweeps.
//
// The stream targets read the fuzz input as a sequence of records (a tiny framing of this
// harness, not a lasercell format), so one input drives a whole conversation:
//   udp_stream:  [u16 LE length][u8 milliseconds since the previous datagram][datagram bytes]...
//   line_scan:   [u8 width/8][u8 lines][u8 flags] then per buffer [u16 LE block id][u8 kind]
//                [image bytes][line timestamps], see LineScanBody.

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "tests/fuzz/harness/fuzz_target.hpp"
#include "triangulation/line_scan.hpp"
#include "triangulation/profile_io.hpp"
#include "triangulation/udp_assembler.hpp"
#include "triangulation/udp_packet.hpp"

namespace lasercell::fuzz {

using triangulation::Profile;
using triangulation::ProfileSet;

static ProfileSet SeedSet(std::uint32_t columns, std::uint32_t joints, std::size_t count) {
  ProfileSet set;
  set.header.image_width = 64;
  set.header.image_height = 48;
  set.header.first_column = 64 - columns;
  set.header.columns = columns;
  set.header.joint_count = joints;
  set.header.robot = joints > 0 ? "vision_robot" : "";
  set.header.metadata = "seed: true\n";
  for (std::size_t i = 0; i < count; ++i) {
    Profile p;
    p.sequence = 10 + i;
    p.timestamp_ns = static_cast<std::int64_t>(1000000 * i);
    p.joints_rad.assign(joints, 0.125 * static_cast<double>(i));
    for (std::uint32_t c = 0; c < columns; ++c) {
      const bool peak = (c + i) % 5 != 0;
      p.row_px.push_back(peak ? 20.5f + 0.25f * static_cast<float>(c) : std::nanf(""));
      p.intensity.push_back(peak ? 0.5f : 0.0f);
      p.width_px.push_back(peak ? 2.0f : 0.0f);
    }
    set.profiles.push_back(p);
  }
  return set;
}

static std::vector<std::string> LcpSeeds() {
  return {triangulation::EncodeProfiles(SeedSet(8, 0, 3)),
          triangulation::EncodeProfiles(SeedSet(16, 6, 2))};
}

LASERCELL_FUZZ_TARGET(lcp, LcpSeeds) {
  const ProfileSet set = triangulation::DecodeProfiles(bytes, "fuzz.lcp");
  const std::string written = triangulation::EncodeProfiles(set);
  ProfileSet again;
  LASERCELL_FUZZ_MUST_ACCEPT(again = triangulation::DecodeProfiles(written, "written.lcp"));
  LASERCELL_FUZZ_ASSERT(triangulation::EncodeProfiles(again) == written,
                        ".lcp: write(read(write(read(x)))) differs from write(read(x))");
}

// --- UDP datagrams and sweep reassembly ---------------------------------------------------------

static void AppendRecord(std::string& out, const std::string& datagram, std::uint8_t dt_ms) {
  const auto n = static_cast<std::uint16_t>(datagram.size());
  out.push_back(static_cast<char>(n & 0xff));
  out.push_back(static_cast<char>(n >> 8));
  out.push_back(static_cast<char>(dt_ms));
  out += datagram;
}

static std::vector<std::string> UdpSeeds() {
  std::vector<std::string> seeds;
  for (const std::size_t bytes_per_datagram : {std::size_t{1472}, std::size_t{600}}) {
    triangulation::DatagramOptions options;
    options.max_datagram_bytes = bytes_per_datagram;
    const auto d = triangulation::EncodeSweepDatagrams(SeedSet(64, 6, 4), options);
    std::string in_order;
    std::string shuffled;
    for (std::size_t i = 0; i < d.datagrams.size(); ++i) {
      AppendRecord(in_order, d.datagrams[i], 1);
      // Reversed pairs, one datagram twice, one lost: what the receiver must account for.
      const std::size_t j = (i % 2 == 0 && i + 1 < d.datagrams.size()) ? i + 1 : i - (i % 2);
      if (j != 3) AppendRecord(shuffled, d.datagrams[j], static_cast<std::uint8_t>(i % 3));
      if (i == 2) AppendRecord(shuffled, d.datagrams[i], 0);
    }
    seeds.push_back(in_order);
    seeds.push_back(shuffled);
  }
  return seeds;
}

// What a delivered sweep must satisfy whatever arrived.
static void CheckSweep(const triangulation::AssembledSweep& sweep) {
  const auto& set = sweep.set;
  const auto& a = sweep.account;
  LASERCELL_FUZZ_ASSERT(a.delivered == set.profiles.size(), "udp: delivered != profiles in set");
  for (std::size_t i = 0; i < set.profiles.size(); ++i) {
    const Profile& p = set.profiles[i];
    LASERCELL_FUZZ_ASSERT(p.row_px.size() == set.header.columns &&
                              p.intensity.size() == set.header.columns &&
                              p.width_px.size() == set.header.columns &&
                              p.joints_rad.size() == set.header.joint_count,
                          "udp: a delivered profile does not match its header");
    LASERCELL_FUZZ_ASSERT(i == 0 || p.sequence > set.profiles[i - 1].sequence,
                          "udp: delivered profiles are not in increasing sequence order");
  }
  for (const triangulation::SequenceRange& r : a.missing) {
    LASERCELL_FUZZ_ASSERT(r.first <= r.last, "udp: a missing range ends before it starts");
  }
}

static std::vector<std::string> DatagramSeeds() {
  triangulation::DatagramOptions options;
  options.max_datagram_bytes = 600;  // two fragments per profile
  return triangulation::EncodeSweepDatagrams(SeedSet(64, 6, 2), options).datagrams;
}

LASERCELL_FUZZ_TARGET(udp_datagram, DatagramSeeds) {
  // One datagram alone, at the default limits: never reads outside `bytes`.
  triangulation::Datagram d;
  const triangulation::DatagramLimits limits;
  if (triangulation::DecodeDatagram(bytes, limits, &d) == triangulation::DatagramStatus::kOk &&
      d.type == triangulation::DatagramType::kFragment) {
    LASERCELL_FUZZ_ASSERT(d.fragment_index < d.fragment_count && d.columns <= limits.max_columns &&
                              d.column_offset + d.column_count <= d.columns,
                          "udp: a datagram accepted with fields beyond its limits");
  }
}

LASERCELL_FUZZ_TARGET(udp_stream, UdpSeeds) {
  triangulation::SweepAssemblyOptions options;
  options.limits.max_columns = 4096;
  options.limits.max_fragments = 64;
  options.reorder_window = 8;
  options.max_sweep_profiles = 256;
  options.max_open_sweeps = 2;
  options.end_grace_ms = 5;
  options.sweep_timeout_ms = 50;
  triangulation::SweepAssembler assembler(options);
  std::int64_t now_ns = 0;
  std::size_t at = 0;
  while (at + 3 <= bytes.size()) {
    const std::size_t n =
        static_cast<unsigned char>(bytes[at]) |
        (static_cast<std::size_t>(static_cast<unsigned char>(bytes[at + 1])) << 8);
    now_ns += 1000000LL * static_cast<unsigned char>(bytes[at + 2]);
    at += 3;
    const std::string_view datagram = bytes.substr(at, n);
    at += datagram.size();
    assembler.Feed(datagram, now_ns);
    while (auto sweep = assembler.TakeFinished(now_ns)) CheckSweep(*sweep);
    LASERCELL_FUZZ_ASSERT(assembler.open_sweeps() <= options.max_open_sweeps,
                          "udp: more sweeps open than max_open_sweeps");
  }
  for (const auto& sweep : assembler.Flush()) CheckSweep(sweep);
}

// --- GigE Vision line-scan buffers
// ----------------------------------------------------------------

static std::vector<std::string> LineScanSeeds() {
  // 16 columns, 4 lines, chunk timestamps; three complete buffers, one incomplete, one skipped id.
  std::string s = {2, 4, 1};
  for (const std::uint16_t id : {1, 2, 3, 5, 6}) {
    s.push_back(static_cast<char>(id & 0xff));
    s.push_back(static_cast<char>(id >> 8));
    s.push_back(id == 3 ? 1 : 0);
    if (id == 3) continue;
    for (int i = 0; i < 16 * 4; ++i) {
      s.push_back(static_cast<char>(i % 3 == 0 ? 0 : 16 * (i % 40)));
      s.push_back(0);
    }
    for (int line = 0; line < 4; ++line) {
      const std::uint64_t t = 1000000ULL * id + 1000ULL * line;
      for (int b = 7; b >= 0; --b) s.push_back(static_cast<char>((t >> (8 * b)) & 0xff));
    }
  }
  return {s};
}

LASERCELL_FUZZ_TARGET(line_scan, LineScanSeeds) {
  if (bytes.size() < 3) return;
  const std::uint32_t width = 8u * (1u + static_cast<unsigned char>(bytes[0]) % 8u);
  const std::uint32_t lines = 1u + static_cast<unsigned char>(bytes[1]) % 8u;
  const bool chunk = (bytes[2] & 1) != 0;
  triangulation::ProfileHeader header;
  header.image_width = 2 * width;
  header.image_height = 256;
  header.first_column = width / 2;
  header.columns = width;
  triangulation::LineScanOptions options;
  options.line_rate_hz = (bytes[2] & 2) != 0 ? 0.0 : 1000.0;
  options.line_timestamp_chunk_id = chunk ? 0x4c54 : 0;
  options.max_sweep_profiles = 64;
  if (!chunk && options.line_rate_hz == 0.0) options.line_rate_hz = 500.0;
  triangulation::LineScanAssembler assembler(header, lines, options);
  const auto check = [&](const triangulation::LineScanSweep& sweep) {
    LASERCELL_FUZZ_ASSERT(sweep.set.profiles.size() == sweep.account.profiles,
                          "line scan: account.profiles != profiles in the sweep");
    for (std::size_t i = 0; i < sweep.set.profiles.size(); ++i) {
      const Profile& p = sweep.set.profiles[i];
      LASERCELL_FUZZ_ASSERT(p.row_px.size() == width, "line scan: a profile of the wrong width");
      LASERCELL_FUZZ_ASSERT(i == 0 || p.sequence > sweep.set.profiles[i - 1].sequence,
                            "line scan: profiles are not in increasing sequence order");
    }
  };
  std::size_t at = 3;
  const std::size_t image_bytes = 2u * width * lines;
  while (at + 3 <= bytes.size()) {
    const std::uint64_t id =
        static_cast<unsigned char>(bytes[at]) |
        (static_cast<std::uint64_t>(static_cast<unsigned char>(bytes[at + 1])) << 8);
    const int kind = static_cast<unsigned char>(bytes[at + 2]) % 4;
    at += 3;
    if (kind == 1) {
      assembler.AddIncomplete(id);
      continue;
    }
    triangulation::LineScanBuffer buffer;
    buffer.frame_id = id;
    buffer.timestamp_ns = static_cast<std::int64_t>(id) * 1000000;
    // kind 2: a buffer of another format; kind 3: one line fewer than declared.
    buffer.pixel_format = kind == 2 ? 0x01080001u : triangulation::kPixelFormatCoord3dC16;
    buffer.width = width;
    buffer.height = lines;
    buffer.x_offset = header.first_column;
    const std::size_t take = kind == 3 ? image_bytes - 2 * width : image_bytes;
    buffer.image = bytes.substr(at, take);
    at += buffer.image.size();
    if (chunk) {
      buffer.line_timestamps = bytes.substr(at, 8u * lines);
      at += buffer.line_timestamps.size();
    }
    if (auto sweep = assembler.AddComplete(buffer)) check(*sweep);
  }
  if (auto sweep = assembler.Finish(triangulation::LineScanEnd::kGap)) check(*sweep);
}

}  // namespace lasercell::fuzz
