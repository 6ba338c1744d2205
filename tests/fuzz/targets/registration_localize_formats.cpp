// Fuzz targets for registration's and localize's files and frames: `.ppfm` PPF models, localize
// options files, job and part files, the robot protocol's binary and ASCII frames (both
// directions), and the STEP/IGES entry point at lasercell's boundary (what reaches OpenCASCADE
// and what comes back).

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/file_util.hpp"
#include "localize/cad_export.hpp"
#include "localize/cad_import.hpp"
#include "localize/job.hpp"
#include "localize/part.hpp"
#include "localize/robot_protocol.hpp"
#include "registration/localize_options_io.hpp"
#include "registration/ppf_model.hpp"
#include "tests/fuzz/harness/fuzz_target.hpp"

namespace lasercell::fuzz {

// 6 faces of a 40 x 30 x 20 mm box, 5 mm grid, outward normals.
static PointCloud BoxCloud() {
  PointCloud c;
  const Eigen::Vector3d size(40, 30, 20);
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3;
    const int v = (axis + 2) % 3;
    for (const double side : {0.0, 1.0}) {
      for (double a = 0; a <= size[u]; a += 5) {
        for (double b = 0; b <= size[v]; b += 5) {
          Eigen::Vector3d p;
          p[axis] = side * size[axis];
          p[u] = a;
          p[v] = b;
          Eigen::Vector3d n = Eigen::Vector3d::Zero();
          n[axis] = side > 0 ? 1 : -1;
          c.positions.push_back(p);
          c.normals.push_back(n);
        }
      }
    }
  }
  return c;
}

static std::vector<std::string> PpfmSeeds() {
  registration::PpfModelOptions options;
  options.sampling_step_relative = 0.1;
  return {registration::PpfModel::Build(BoxCloud(), options).Serialize()};
}

LASERCELL_FUZZ_TARGET(ppfm, PpfmSeeds) {
  const auto model = registration::PpfModel::Deserialize(bytes, "fuzz.ppfm");
  const std::string written = model.Serialize();
  std::string again;
  LASERCELL_FUZZ_MUST_ACCEPT(
      again = registration::PpfModel::Deserialize(written, "written.ppfm").Serialize());
  LASERCELL_FUZZ_ASSERT(again == written,
                        ".ppfm: write(read(write(read(x)))) differs from write(read(x))");
}

static std::vector<std::string> OptionsSeeds() {
  const std::string head = "format: lasercell.localize_options\nversion: 1\n";
  return {
      head +
          "threads: 2\nmax_instances: 3\nview_direction: [0, 0, -1]\n"
          "roi: {min_mm: [-200, -150, -20], max_mm: [200, 150, 120]}\n"
          "normals: {k: 12, radius_mm: 2.5}\nrecompute_normals: false\n",
      head + "model:\n" + registration::PpfModelOptionsYaml(registration::PpfModelOptions(), "  ")};
}

LASERCELL_FUZZ_TARGET(localize_options, OptionsSeeds) {
  registration::ParseLocalizeOptions(std::string(bytes), "fuzz_options.yaml");
}

static constexpr const char* kPartSeed =
    "format: lasercell.part\nversion: 1\nname: block\nmodel: block.stl\nunits: cm\n"
    "grasps:\n  top:\n"
    "    part_from_grasp: {translation_mm: [40, 30, 20], rotation_wxyz: [0, 1, 0, 0]}\n"
    "    description: suction cup on the top face\n    refine_radius_mm: 25.5\n"
    "stable_poses:\n  up_in_part: [[0, 0, 1], [0, 0, -1]]\n  max_tilt_deg: 10\n"
    "symmetry: {kind: discrete, axis_in_part: [0, 0, 1], order: 2}\n"
    "cad: {sampling_step_mm: 2}\nmodel_options: {sampling_step_relative: 0.05}\n"
    "form_deviation: {rms_mm: 0.17, correlation_mm: 35}\n";

static std::vector<std::string> PartSeeds() { return {kPartSeed}; }

LASERCELL_FUZZ_TARGET(part, PartSeeds) {
  const localize::PartDefinition part =
      localize::ParsePartFile(std::string(bytes), "/parts/fuzz.part.yaml");
  const std::string written = localize::PartFileYaml(part);
  std::string again;
  LASERCELL_FUZZ_MUST_ACCEPT(
      again = localize::PartFileYaml(localize::ParsePartFile(written, "/parts/fuzz.part.yaml")));
  LASERCELL_FUZZ_ASSERT(again == written,
                        "part file: write(read(write(read(x)))) differs from write(read(x))");
}

// The job file names part files; the scratch folder holds one (seat.part.yaml) so a job can
// get past its parts list.
static std::vector<std::string> JobSeeds() {
  return {
      "format: lasercell.job\nversion: 1\ncell: cal/cell.yaml\ncamera: cal/camera.cameramodel\n"
      "source: {file: seat.lcp}\nlaser: laser_2\ntrajectory: {linear: records/linear.yaml}\n"
      "target_frame: cell\nroi: {min_mm: [-300, -300, -50], max_mm: [300, 300, 200]}\n"
      "support_plane: {normal: [0, 0, 1], offset_mm: 12.5, max_penetration_mm: 2}\n"
      "parts:\n  - {part: seat.part.yaml, instances: 2}\n"
      "grasp_tolerance_mm: 8\nscan_noise_mm: 0.05\nmax_rmse_factor: 4\nthreads: 1\n"
      "model_cache: cache\nlocalize: {max_verified_clusters: 7, icp: {max_iterations: 12}}\n",
      "format: lasercell.job\nversion: 1\ncell: cell.yaml\ncamera: c.cameramodel\n"
      "source: {file: s.lcp}\ntrajectory: {robot: vision_robot}\n"
      "parts: [{part: seat.part.yaml}]\n"};
}

LASERCELL_FUZZ_TARGET(job, JobSeeds) {
  static const std::string folder = [] {
    io::WriteFileAtomically(ScratchDir() + "/seat.part.yaml", kPartSeed);
    return ScratchDir();
  }();
  localize::ParseJobFile(std::string(bytes), folder + "/job.yaml");
}

// --- robot protocol ---------------------------------------------------------------------------

static std::vector<std::string> RobotSeeds() {
  localize::RobotRequest look;
  look.command = localize::RobotCommand::kLook;
  look.request_id = 7;
  Eigen::Isometry3d flange = Eigen::Isometry3d::Identity();
  flange.translation() = Eigen::Vector3d(400, -20, 600);
  look.base_from_flange = flange;
  localize::RobotReply reply;
  reply.status = localize::ReplyStatus::kOk;
  reply.request_id = 7;
  reply.part_index = 0;
  reply.part = "seat";
  reply.instance = 1;
  reply.target_from_grasp.translation() = Eigen::Vector3d(812.25, -40.5, 93);
  reply.instances_left = 1;
  reply.position_sigma_mm = 0.12;
  reply.latency_ms = 3.5;
  // One byte chooses what the rest is decoded as (see RobotBody).
  return {WithSelector(0, localize::EncodeBinaryRequest(look)),
          WithSelector(1, localize::EncodeAsciiRequest(look)),
          WithSelector(2, localize::EncodeBinaryReply(reply)),
          WithSelector(3, localize::EncodeAsciiReply(reply))};
}

// Equal replies, poses and numbers to the encodings' rounding (0.001 mm / deg / ms).
static bool SameReply(const localize::RobotReply& a, const localize::RobotReply& b) {
  const auto near = [](double x, double y) { return std::abs(x - y) <= 2e-3 * (1 + std::abs(x)); };
  const Eigen::Matrix4d d = a.target_from_grasp.matrix() - b.target_from_grasp.matrix();
  return a.status == b.status && a.request_id == b.request_id && a.part_index == b.part_index &&
         a.part == b.part && a.instance == b.instance && a.instances_left == b.instances_left &&
         d.topLeftCorner<3, 3>().cwiseAbs().maxCoeff() < 1e-4 &&
         near(a.target_from_grasp.translation().norm(), b.target_from_grasp.translation().norm()) &&
         d.topRightCorner<3, 1>().cwiseAbs().maxCoeff() <=
             2e-3 * (1 + a.target_from_grasp.translation().norm()) &&
         near(a.position_sigma_mm, b.position_sigma_mm) && near(a.latency_ms, b.latency_ms);
}

static std::string_view Line(std::string_view s) {
  if (!s.empty() && s.back() == '\n') s.remove_suffix(1);
  return s;
}

LASERCELL_FUZZ_TARGET(robot_protocol, RobotSeeds) {
  if (bytes.empty()) return;
  const int kind = static_cast<unsigned char>(bytes[0]) % 4;
  const std::string_view frame = bytes.substr(1);
  const auto same_request = [](const localize::RobotDecode& a, const localize::RobotDecode& b) {
    return a.request && b.request && a.request->command == b.request->command &&
           a.request->request_id == b.request->request_id &&
           a.request->base_from_flange.has_value() == b.request->base_from_flange.has_value();
  };
  if (kind == 0) {
    const localize::RobotDecode d = localize::DecodeBinaryRequest(frame);
    LASERCELL_FUZZ_ASSERT(d.request.has_value() != !d.error.empty(),
                          "robot protocol: a binary decode is neither a request nor an error");
    if (d.request) {
      LASERCELL_FUZZ_ASSERT(
          same_request(d, localize::DecodeBinaryRequest(localize::EncodeBinaryRequest(*d.request))),
          "robot protocol: a binary request does not survive encode -> decode");
    }
  } else if (kind == 1) {
    const localize::RobotDecode d = localize::DecodeAsciiRequest(frame);
    LASERCELL_FUZZ_ASSERT(d.request.has_value() != !d.error.empty(),
                          "robot protocol: an ASCII decode is neither a request nor an error");
    if (d.request) {
      LASERCELL_FUZZ_ASSERT(same_request(d, localize::DecodeAsciiRequest(
                                                Line(localize::EncodeAsciiRequest(*d.request)))),
                            "robot protocol: an ASCII request does not survive encode -> decode");
    }
  } else {
    // Replies carry the pose as rounded numbers (mm, degrees): a reply that decodes must come
    // back from encode -> decode as the same reply, to that rounding.
    const bool binary = kind == 2;
    const auto decode = [&](std::string_view f) {
      return binary ? localize::DecodeBinaryReply(f) : localize::DecodeAsciiReply(Line(f));
    };
    if (const auto reply = decode(frame)) {
      const auto again =
          decode(binary ? localize::EncodeBinaryReply(*reply) : localize::EncodeAsciiReply(*reply));
      LASERCELL_FUZZ_ASSERT(again.has_value(), "robot protocol: an encoded reply does not decode");
      LASERCELL_FUZZ_ASSERT(SameReply(*reply, *again),
                            "robot protocol: a reply changed through encode -> decode");
    }
  }
}

// --- STEP / IGES --------------------------------------------------------------------------------

static std::vector<std::string> CadSeeds() {
  localize::CadSolid solid;
  localize::CadPrimitive box;
  box.size_mm = Eigen::Vector3d(40, 30, 10);
  localize::CadPrimitive hole;
  hole.kind = localize::CadPrimitive::kCylinder;
  hole.size_mm = Eigen::Vector3d(5, 10, 0);
  hole.part_from_primitive.translation() = Eigen::Vector3d(20, 15, 0);
  hole.subtract = true;
  solid.primitives = {box, hole};
  std::vector<std::string> seeds;
  const std::string step = ScratchDir() + "/seed.step";
  const std::string iges = ScratchDir() + "/seed.igs";
  localize::WriteCadSolid(step, solid);
  localize::WriteCadSolid(iges, solid, "inch");
  seeds.push_back(WithSelector(0, io::ReadFileBytes(step)));
  seeds.push_back(WithSelector(1, io::ReadFileBytes(iges)));
  return seeds;
}

// The first byte chooses the extension (odd: IGES, even: STEP) the rest is written under.
LASERCELL_FUZZ_TARGET(cad, CadSeeds) {
  if (bytes.empty()) return;
  const bool iges = (static_cast<unsigned char>(bytes[0]) & 1) != 0;
  const std::string path = ScratchDir() + (iges ? "/fuzz.igs" : "/fuzz.step");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data() + 1, static_cast<std::streamsize>(bytes.size() - 1));
  }
  localize::CadImportOptions options;
  options.sampling_step_mm = 2.0;  // bounded work per input on the seeds' 40 mm part
  options.timeout_s = 10.0;        // a hang is refused well within libFuzzer's -timeout
  const localize::CadModel model = localize::ReadCadModel(path, options);
  const auto n = static_cast<int>(model.mesh.vertices.size());
  for (const Eigen::Vector3i& f : model.mesh.faces) {
    LASERCELL_FUZZ_ASSERT((f.array() >= 0).all() && (f.array() < n).all(),
                          "CAD: a face indexes a vertex that does not exist");
  }
  for (std::size_t i = 0; i < model.samples.size(); ++i) {
    LASERCELL_FUZZ_ASSERT(model.samples.positions[i].allFinite(), "CAD: a non-finite sample");
    LASERCELL_FUZZ_ASSERT(std::abs(model.samples.normals[i].norm() - 1.0) < 1e-6,
                          "CAD: a sample normal that is not unit length");
  }
}

}  // namespace lasercell::fuzz
