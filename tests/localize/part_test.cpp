// Part files (localize/part.hpp) and part models from meshes (localize/part_model.hpp).
#include "localize/part.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "core/io/file_util.hpp"
#include "core/io/mesh_io.hpp"
#include "localize/part_model.hpp"
#include "tests/cli_util.hpp"

namespace lasercell::localize {
namespace {

// A closed box [0,a] x [0,b] x [0,c], outward counter-clockwise faces.
TriangleMesh Box(double a, double b, double c) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.positions.emplace_back(i & 1 ? a : 0.0, i & 2 ? b : 0.0, i & 4 ? c : 0.0);
  }
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

constexpr const char* kPart =
    "format: lasercell.part\n"
    "version: 1\n"
    "name: block\n"
    "model: block.stl\n"
    "units: cm\n"
    "grasps:\n"
    "  top:\n"
    "    part_from_grasp: {translation_mm: [40, 30, 20], rotation_wxyz: [0, 1, 0, 0]}\n"
    "    description: suction cup on the top face\n"
    "    refine_radius_mm: 25.5\n"
    "stable_poses:\n"
    "  up_in_part: [[0, 0, 1], [0, 0, -1]]\n"
    "  max_tilt_deg: 10\n"
    "symmetry: {kind: discrete, axis_in_part: [0, 0, 1], order: 2}\n"
    "cad: {sampling_step_mm: 2}\n"
    "model_options: {sampling_step_relative: 0.05}\n"
    "form_deviation: {rms_mm: 0.17, correlation_mm: 35}\n";

TEST(PartFile, EveryFieldIsReadAndWrittenBackTheSame) {
  const PartDefinition part = ParsePartFile(kPart, "/parts/block.part.yaml");
  EXPECT_EQ(part.name, "block");
  EXPECT_EQ(part.model_path, "/parts/block.stl");  // relative to the part file
  EXPECT_EQ(part.units, "cm");
  ASSERT_EQ(part.grasps.size(), 1u);
  EXPECT_EQ(part.Grasp("top").part_from_grasp.translation_mm, Eigen::Vector3d(40, 30, 20));
  EXPECT_EQ(part.grasps[0].description, "suction cup on the top face");
  EXPECT_EQ(part.grasps[0].refine_radius_mm, 25.5);
  ASSERT_EQ(part.stable_up_in_part.size(), 2u);
  EXPECT_NEAR(part.max_tilt_rad, 10.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(part.symmetry.kind, PartSymmetry::Kind::kDiscrete);
  EXPECT_EQ(part.symmetry.order, 2);
  EXPECT_EQ(part.cad.sampling_step_mm, 2.0);
  EXPECT_EQ(part.model_options.sampling_step_relative, 0.05);
  EXPECT_EQ(part.form_deviation.rms_mm, 0.17);
  EXPECT_EQ(part.form_deviation.correlation_mm, 35.0);
  EXPECT_NE(ErrorOf([&] { part.Grasp("side"); }).find("has no grasp 'side' (it has: top)"),
            std::string::npos);

  const test::TestDir dir("part_file");
  const std::string path = dir.File("block.part.yaml");
  WritePartFile(path, part);
  const PartDefinition back = ReadPartFile(path);
  EXPECT_EQ(PartFileYaml(back), PartFileYaml(part));
  EXPECT_EQ(back.grasps[0].part_from_grasp.rotation.coeffs(),
            part.grasps[0].part_from_grasp.rotation.coeffs());
  EXPECT_EQ(back.max_tilt_rad, part.max_tilt_rad);
  EXPECT_EQ(back.model_options.sampling_step_relative, 0.05);
  EXPECT_EQ(back.grasps[0].refine_radius_mm, 25.5);
  EXPECT_EQ(back.form_deviation.rms_mm, 0.17);
  EXPECT_EQ(back.form_deviation.correlation_mm, 35.0);
}

// Without the key the model is taken as exact, and nothing is written back for it; with only
// rms_mm the correlation length is its default.
TEST(PartFile, FormDeviationIsOptionalAndDefaultsToAnExactModel) {
  const std::string head = "format: lasercell.part\nversion: 1\nname: p\nmodel: a.stl\nunits: mm\n";
  const PartDefinition exact = ParsePartFile(head, "p.yaml");
  EXPECT_EQ(exact.form_deviation.rms_mm, 0.0);
  EXPECT_EQ(PartFileYaml(exact).find("form_deviation"), std::string::npos);
  const PartDefinition warped = ParsePartFile(head + "form_deviation: {rms_mm: 0.3}\n", "p.yaml");
  EXPECT_EQ(warped.form_deviation.rms_mm, 0.3);
  EXPECT_EQ(warped.form_deviation.correlation_mm, FormDeviation{}.correlation_mm);
}

TEST(PartFile, BadFieldsNameTheFileAndTheField) {
  const auto error = [](const std::string& text) {
    return ErrorOf([&] { ParsePartFile(text, "p.yaml"); });
  };
  const std::string head = "format: lasercell.part\nversion: 1\nname: p\n";
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\ncolour: red\n").find("colour"),
            std::string::npos);
  EXPECT_NE(error(head).find("field 'model' is required"), std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\n").find("field 'units' is required for a mesh"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.step\nunits: mm\n").find("STEP and IGES files carry their own"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: furlong\n").find("expected mm, cm, m or inch"),
            std::string::npos);
  EXPECT_NE(error("format: lasercell.job\nversion: 1\n").find("expected 'lasercell.part'"),
            std::string::npos);
  EXPECT_NE(error("format: lasercell.part\nversion: 2\n").find("this build reads"),
            std::string::npos);
  EXPECT_NE(error("format: lasercell.part\nversion: 1\nname: Big Part\nmodel: a.stl\nunits: mm\n")
                .find("lower snake case"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nstable_poses: {up_in_part: [[0, 0, 2]]}\n")
                .find("not a unit vector"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nsymmetry: {kind: discrete, axis_in_part: "
                         "[0, 0, 1], order: 1}\n")
                .find("order must be >= 2"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nmodel_options: {sampling_step: 3}\n")
                .find("sampling_step"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\ngrasps: {g: {part_from_grasp: {translation_mm: "
                         "[0, 0, 0], rotation_wxyz: [1, 0, 0, 0]}, refine_radius_mm: -5}}\n")
                .find("grasps.g.refine_radius_mm must be in [0, 10000]"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\ncad: {sampling_step_mm: -1}\n")
                .find("sampling_step_mm"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nform_deviation: {rms_mm: -0.1}\n")
                .find("field 'form_deviation.rms_mm' must be in [0, 100] mm"),
            std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nform_deviation: {rms_mm: 0.1, "
                         "correlation_mm: 0}\n")
                .find("correlation_mm' must be in (0, 10000] mm"),
            std::string::npos);
  EXPECT_NE(
      error(head + "model: a.stl\nunits: mm\nform_deviation: {correlation_mm: 5}\n").find("rms_mm"),
      std::string::npos);
  EXPECT_NE(error(head + "model: a.stl\nunits: mm\nform_deviation: {rms_mm: 0.1, sigma: 1}\n")
                .find("sigma"),
            std::string::npos);
}

TEST(PartModel, MeshSurfaceSamplesLieOnTheFacesWithOutwardNormalsAtTheRequestedDensity) {
  const TriangleMesh box = Box(40, 30, 20);
  const PointCloud samples = SampleMeshSurface(box, 1.0);
  const double area = 2 * (40 * 30 + 40 * 20 + 30 * 20);
  // ceil(area / step^2) per triangle: between the area and area + one per triangle.
  EXPECT_GE(samples.size(), static_cast<std::size_t>(area));
  EXPECT_LE(samples.size(), static_cast<std::size_t>(area) + 12);
  const Eigen::Vector3d centre(20, 15, 10);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Eigen::Vector3d& p = samples.positions[i];
    const Eigen::Vector3d& n = samples.normals[i];
    // On the surface: one coordinate at a face, the others inside.
    const double d = std::min({std::abs(p.x()), std::abs(p.x() - 40), std::abs(p.y()),
                               std::abs(p.y() - 30), std::abs(p.z()), std::abs(p.z() - 20)});
    ASSERT_LT(d, 1e-9) << i;
    ASSERT_GT(n.dot(p - centre), 0.0) << "inward normal at " << i;
    ASSERT_NEAR(n.norm(), 1.0, 1e-12);
  }
  // Spread over the face, not clumped: each 5 x 5 mm cell of the top face holds samples.
  int empty_cells = 0;
  for (int cx = 0; cx < 8; ++cx) {
    for (int cy = 0; cy < 6; ++cy) {
      bool hit = false;
      for (const Eigen::Vector3d& p : samples.positions) {
        hit |= std::abs(p.z() - 20) < 1e-9 && p.x() >= 5 * cx && p.x() < 5 * (cx + 1) &&
               p.y() >= 5 * cy && p.y() < 5 * (cy + 1);
      }
      empty_cells += hit ? 0 : 1;
    }
  }
  EXPECT_EQ(empty_cells, 0);
  EXPECT_EQ(SampleMeshSurface(box, 1.0).positions, samples.positions);  // deterministic
  EXPECT_THROW(SampleMeshSurface(TriangleMesh{}, 1.0), InputError);
}

TEST(PartModel, MeshPartsAreScaledToMmBuiltOnceAndThenLoadedFromTheCache) {
  const test::TestDir dir("part_model");
  io::WriteStlMesh(dir.File("block.stl"), Box(4, 3, 2));  // cm
  io::WriteFileAtomically(dir.File("block.part.yaml"), kPart);
  const PartDefinition part = ReadPartFile(dir.File("block.part.yaml"));
  PartModelOptions options;
  options.threads = 1;
  const PartModel built = LoadPartModel(part, options);
  EXPECT_FALSE(built.from_cache);
  EXPECT_EQ(built.source_format, "stl");
  EXPECT_NEAR(built.bounds.max().x(), 40.0, 1e-5);  // 4 cm
  EXPECT_NEAR(built.ppf.diameter_mm(), std::sqrt(40 * 40 + 30 * 30 + 20 * 20), 2.0);
  ASSERT_TRUE(std::filesystem::is_regular_file(built.cache_file)) << built.cache_file;
  EXPECT_NE(built.cache_file.find(".lasercell-cache/block-"), std::string::npos);
  const PartModel cached = LoadPartModel(part, options);
  EXPECT_TRUE(cached.from_cache);
  EXPECT_EQ(cached.ppf.Serialize(), built.ppf.Serialize());
  EXPECT_NE(PartModelSummary(cached).find("loaded from the cache"), std::string::npos);
  EXPECT_NE(PartModelSummary(cached).find("form deviation from the model: 0.170 mm RMS over 35 mm"),
            std::string::npos)
      << PartModelSummary(cached);
  // Another option is another model, under another name.
  PartDefinition coarser = part;
  coarser.model_options.sampling_step_relative = 0.08;
  const PartModel other = LoadPartModel(coarser, options);
  EXPECT_FALSE(other.from_cache);
  EXPECT_NE(other.cache_file, built.cache_file);
  // An edited model file changes the digest.
  io::WriteStlMesh(dir.File("block.stl"), Box(4, 3, 2.5));
  EXPECT_NE(PartModelDigest(part), built.digest);
  EXPECT_FALSE(LoadPartModel(part, options).from_cache);
}

TEST(PartModel, MissingEmptyOrMisplacedModelsAreClearErrors) {
  const test::TestDir dir("part_model_bad");
  PartDefinition part;
  part.name = "thing";
  part.file = dir.File("thing.part.yaml");
  part.model = "thing.stl";
  part.model_path = dir.File("thing.stl");
  part.units = "mm";
  EXPECT_NE(ErrorOf([&] { LoadPartModel(part); }).find("does not exist"), std::string::npos);
  io::WriteFileAtomically(dir.File("thing.stl"), "solid empty\nendsolid empty\n");
  EXPECT_NE(ErrorOf([&] { LoadPartModel(part); }).find("holds no triangles"), std::string::npos);
  io::WriteStlMesh(dir.File("thing.stl"), Box(40, 30, 20));
  GraspFrame far;
  far.name = "far";
  far.part_from_grasp.translation_mm = Eigen::Vector3d(400, 0, 0);  // metres typed as cm?
  part.grasps.push_back(far);
  PartModelOptions options;
  options.use_cache = false;
  EXPECT_NE(ErrorOf([&] { LoadPartModel(part, options); }).find("grasps.far.part_from_grasp lies"),
            std::string::npos);
}

}  // namespace
}  // namespace lasercell::localize
