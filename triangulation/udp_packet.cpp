#include "triangulation/udp_packet.hpp"

#include <algorithm>
#include <cstring>

#include "core/error.hpp"
#include "core/io/byte_order.hpp"

namespace lasercell::triangulation {

namespace {

using io::GetLe;
using io::PutLe;

constexpr std::size_t kCommonBytes = 32;
constexpr std::size_t kMaxUdpPayload = 65507;

void PutCommon(DatagramType type, const DatagramOptions& options, std::uint64_t sequence,
               std::int64_t timestamp_ns, std::string* out) {
  out->append(kDatagramMagic);
  PutLe<std::uint8_t>(out, kDatagramVersion);
  PutLe<std::uint8_t>(out, static_cast<std::uint8_t>(type));
  PutLe<std::uint16_t>(out, 0);
  PutLe<std::uint32_t>(out, options.sensor_id);
  PutLe<std::uint32_t>(out, options.sweep_id);
  PutLe<std::uint64_t>(out, sequence);
  PutLe<std::int64_t>(out, timestamp_ns);
}

std::string Marker(DatagramType type, const ProfileSet& set, const DatagramOptions& options,
                   const std::string& header_bytes) {
  std::string out;
  const bool end = type == DatagramType::kEnd;
  const std::uint64_t first = set.profiles.empty() ? 0 : set.profiles.front().sequence;
  const std::uint64_t last = set.profiles.empty() ? 0 : set.profiles.back().sequence;
  PutCommon(type, options, first, options.send_time_ns, &out);
  PutLe<std::uint64_t>(&out, end ? last : 0);
  PutLe<std::uint64_t>(&out, end ? set.profiles.size() : 0);
  out += header_bytes;
  return out;
}

DatagramStatus DecodeMarker(std::string_view bytes, Datagram* out) {
  if (bytes.size() < kMarkerHeaderBytes) return DatagramStatus::kTooShort;
  out->last_sequence = GetLe<std::uint64_t>(bytes.data() + 32);
  out->profile_count = GetLe<std::uint64_t>(bytes.data() + 40);
  if (out->type == DatagramType::kBegin && (out->last_sequence != 0 || out->profile_count != 0)) {
    return DatagramStatus::kBadHeader;
  }
  if (out->type == DatagramType::kEnd &&
      (out->last_sequence < out->sequence ||
       out->profile_count > out->last_sequence - out->sequence + 1)) {
    return DatagramStatus::kBadHeader;
  }
  try {
    const ProfileSet set = DecodeProfiles(bytes.substr(kMarkerHeaderBytes), "datagram");
    if (!set.profiles.empty()) return DatagramStatus::kBadHeader;
    out->header = set.header;
  } catch (const InputError&) {
    return DatagramStatus::kBadHeader;
  }
  return DatagramStatus::kOk;
}

DatagramStatus DecodeFragment(std::string_view bytes, const DatagramLimits& limits, Datagram* out) {
  if (bytes.size() < kFragmentHeaderBytes) return DatagramStatus::kTooShort;
  const char* p = bytes.data();
  out->fragment_index = GetLe<std::uint16_t>(p + 32);
  out->fragment_count = GetLe<std::uint16_t>(p + 34);
  out->columns = GetLe<std::uint32_t>(p + 36);
  out->column_offset = GetLe<std::uint32_t>(p + 40);
  out->column_count = GetLe<std::uint32_t>(p + 44);
  out->joint_count = GetLe<std::uint16_t>(p + 48);
  const auto reserved = GetLe<std::uint16_t>(p + 50);
  out->first_column = GetLe<std::uint32_t>(p + 52);
  out->image_width = GetLe<std::uint32_t>(p + 56);
  out->image_height = GetLe<std::uint32_t>(p + 60);
  if (out->fragment_count == 0 || out->fragment_count > limits.max_fragments ||
      out->fragment_index >= out->fragment_count) {
    return DatagramStatus::kBadFragment;
  }
  if (out->joint_count > limits.max_joints) return DatagramStatus::kBadJoints;
  const std::uint64_t offset = out->column_offset;
  if (out->columns == 0 || out->columns > limits.max_columns || out->column_count == 0 ||
      offset + out->column_count > out->columns || out->image_height == 0 ||
      static_cast<std::uint64_t>(out->first_column) + out->columns > out->image_width) {
    return DatagramStatus::kBadColumns;
  }
  if (reserved != 0) return DatagramStatus::kBadLength;
  const std::uint64_t expected =
      kFragmentHeaderBytes + 8ull * out->joint_count + 12ull * out->column_count;
  if (bytes.size() != expected) return DatagramStatus::kBadLength;
  out->joints = p + kFragmentHeaderBytes;
  out->columns_data = out->joints + 8 * out->joint_count;
  return DatagramStatus::kOk;
}

}  // namespace

const char* DatagramStatusName(DatagramStatus status) {
  switch (status) {
    case DatagramStatus::kOk:
      return "ok";
    case DatagramStatus::kTooShort:
      return "too_short";
    case DatagramStatus::kBadMagic:
      return "bad_magic";
    case DatagramStatus::kBadVersion:
      return "bad_version";
    case DatagramStatus::kBadType:
      return "bad_type";
    case DatagramStatus::kBadLength:
      return "bad_length";
    case DatagramStatus::kBadFragment:
      return "bad_fragment";
    case DatagramStatus::kBadColumns:
      return "bad_columns";
    case DatagramStatus::kBadJoints:
      return "bad_joints";
    case DatagramStatus::kBadHeader:
      return "bad_header";
    case DatagramStatus::kCount:
      break;
  }
  return "unknown";
}

DatagramStatus DecodeDatagram(std::string_view bytes, const DatagramLimits& limits, Datagram* out) {
  if (bytes.size() < kCommonBytes) return DatagramStatus::kTooShort;
  if (bytes.substr(0, kDatagramMagic.size()) != kDatagramMagic) return DatagramStatus::kBadMagic;
  const char* p = bytes.data();
  if (GetLe<std::uint8_t>(p + 4) != kDatagramVersion) return DatagramStatus::kBadVersion;
  const auto type = GetLe<std::uint8_t>(p + 5);
  if (type < 1 || type > 3) return DatagramStatus::kBadType;
  if (GetLe<std::uint16_t>(p + 6) != 0) return DatagramStatus::kBadLength;
  out->type = static_cast<DatagramType>(type);
  out->sensor_id = GetLe<std::uint32_t>(p + 8);
  out->sweep_id = GetLe<std::uint32_t>(p + 12);
  out->sequence = GetLe<std::uint64_t>(p + 16);
  out->timestamp_ns = GetLe<std::int64_t>(p + 24);
  if (out->type == DatagramType::kFragment) return DecodeFragment(bytes, limits, out);
  return DecodeMarker(bytes, out);
}

void CopyFragmentColumns(const Datagram& fragment, Profile* profile) {
  const std::size_t n = fragment.column_count;
  const char* q = fragment.columns_data;
  for (auto* vec : {&profile->row_px, &profile->intensity, &profile->width_px}) {
    float* dst = vec->data() + fragment.column_offset;
    for (std::size_t c = 0; c < n; ++c, q += 4) dst[c] = GetLe<float>(q);
  }
  profile->joints_rad.resize(fragment.joint_count);
  for (std::size_t j = 0; j < fragment.joint_count; ++j) {
    profile->joints_rad[j] = GetLe<double>(fragment.joints + 8 * j);
  }
  profile->sequence = fragment.sequence;
  profile->timestamp_ns = fragment.timestamp_ns;
}

void DatagramOptions::Check() const {
  if (max_datagram_bytes < kFragmentHeaderBytes + 12 + 8 * 64 ||
      max_datagram_bytes > kMaxUdpPayload) {
    throw OptionError("DatagramOptions.max_datagram_bytes = " + std::to_string(max_datagram_bytes) +
                      " must be in [" + std::to_string(kFragmentHeaderBytes + 12 + 8 * 64) + ", " +
                      std::to_string(kMaxUdpPayload) + "] (1472 for Ethernet, 8972 for jumbo)");
  }
}

SweepDatagrams EncodeSweepDatagrams(const ProfileSet& set, const DatagramOptions& options) {
  options.Check();
  const ProfileHeader& h = set.header;
  const std::string header_bytes = EncodeProfileHeader(h, 0);
  if (kMarkerHeaderBytes + header_bytes.size() > options.max_datagram_bytes) {
    throw InputError("the sweep's header (" + std::to_string(header_bytes.size()) +
                     " bytes with robot name and metadata) does not fit in one datagram of " +
                     std::to_string(options.max_datagram_bytes) +
                     " bytes; shorten the metadata or allow larger datagrams");
  }
  const std::size_t per_fragment =
      (options.max_datagram_bytes - kFragmentHeaderBytes - 8 * h.joint_count) / 12;
  const std::size_t fragments = (h.columns + per_fragment - 1) / per_fragment;
  if (fragments > 65535) {
    throw InputError("a profile of " + std::to_string(h.columns) +
                     " columns needs more than 65535 datagrams; allow larger datagrams");
  }
  SweepDatagrams out;
  out.datagrams.reserve(set.profiles.size() * fragments + 2);
  out.datagrams.push_back(Marker(DatagramType::kBegin, set, options, header_bytes));
  out.profile_of.push_back(-1);
  for (std::size_t i = 0; i < set.profiles.size(); ++i) {
    const Profile& prof = set.profiles[i];
    CheckProfile(h, prof, "profile " + std::to_string(i));
    if (i > 0 && prof.sequence <= set.profiles[i - 1].sequence) {
      throw InputError("profile " + std::to_string(i) + ": sequence " +
                       std::to_string(prof.sequence) + " does not follow " +
                       std::to_string(set.profiles[i - 1].sequence) +
                       "; a sweep's sequence numbers must increase");
    }
    for (std::size_t f = 0; f < fragments; ++f) {
      const std::size_t c0 = f * per_fragment;
      const std::size_t n = std::min<std::size_t>(per_fragment, h.columns - c0);
      std::string d;
      d.reserve(kFragmentHeaderBytes + 8 * h.joint_count + 12 * n);
      PutCommon(DatagramType::kFragment, options, prof.sequence, prof.timestamp_ns, &d);
      PutLe<std::uint16_t>(&d, static_cast<std::uint16_t>(f));
      PutLe<std::uint16_t>(&d, static_cast<std::uint16_t>(fragments));
      PutLe<std::uint32_t>(&d, h.columns);
      PutLe<std::uint32_t>(&d, static_cast<std::uint32_t>(c0));
      PutLe<std::uint32_t>(&d, static_cast<std::uint32_t>(n));
      PutLe<std::uint16_t>(&d, static_cast<std::uint16_t>(h.joint_count));
      PutLe<std::uint16_t>(&d, 0);
      PutLe<std::uint32_t>(&d, h.first_column);
      PutLe<std::uint32_t>(&d, h.image_width);
      PutLe<std::uint32_t>(&d, h.image_height);
      for (double q : prof.joints_rad) PutLe<double>(&d, q);
      for (const auto* vec : {&prof.row_px, &prof.intensity, &prof.width_px}) {
        for (std::size_t c = c0; c < c0 + n; ++c) PutLe<float>(&d, (*vec)[c]);
      }
      out.datagrams.push_back(std::move(d));
      out.profile_of.push_back(static_cast<std::int64_t>(i));
    }
  }
  out.datagrams.push_back(Marker(DatagramType::kEnd, set, options, header_bytes));
  out.profile_of.push_back(-1);
  return out;
}

}  // namespace lasercell::triangulation
