#include "datasets/chair_parts.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "core/error.hpp"
#include "datasets/form_deviation.hpp"
#include "localize/cad_import.hpp"

namespace lasercell::datasets {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
// Features that join another primitive reach this far into it, so no two faces of the Boolean
// operands coincide (coplanar operands are where Boolean kernels are fragile).
constexpr double kEmbedMm = 2.0;

void Positive(double v, const std::string& what, const char* field) {
  if (!(v > 0) || !std::isfinite(v)) {
    throw OptionError(what + "." + field + " must be a positive number (mm), got " +
                      std::to_string(v));
  }
}

void Require(bool ok, const std::string& what, const std::string& message) {
  if (!ok) throw OptionError(what + "." + message);
}

// The box [0, size] placed with its corner at `corner` and its axes along `rotation`'s columns.
localize::CadPrimitive Box(const Eigen::Vector3d& corner, const Eigen::Matrix3d& rotation,
                           const Eigen::Vector3d& size) {
  localize::CadPrimitive p;
  p.kind = localize::CadPrimitive::kBox;
  p.part_from_primitive.linear() = rotation;
  p.part_from_primitive.translation() = corner;
  p.size_mm = size;
  return p;
}

localize::CadPrimitive Box(const Eigen::Vector3d& corner, const Eigen::Vector3d& size) {
  return Box(corner, Eigen::Matrix3d::Identity(), size);
}

// A cylinder of `radius` from `base` along the unit column 2 of `rotation` for `height`.
localize::CadPrimitive Cylinder(const Eigen::Vector3d& base, const Eigen::Matrix3d& rotation,
                                double radius, double height, bool subtract) {
  localize::CadPrimitive p;
  p.kind = localize::CadPrimitive::kCylinder;
  p.part_from_primitive.linear() = rotation;
  p.part_from_primitive.translation() = base;
  p.size_mm = Eigen::Vector3d(radius, height, 1.0);
  p.subtract = subtract;
  return p;
}

Eigen::Matrix3d RotY(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

// A square bar of half-diagonal `depth` centred at `center`, its axis along part axis `axis`
// (0 = x, 2 = z) for `length`, turned 45 deg about that axis: centred on a face normal to the
// other axis, it stands out of it as a roof of two 45 deg slopes, `depth` high.
localize::CadPrimitive RoofBar(const Eigen::Vector3d& center, int axis, double length,
                               double depth) {
  const double side = depth * std::sqrt(2.0);
  Eigen::Vector3d size(side, side, side);
  size[axis] = length;
  const Eigen::Vector3d along = axis == 0 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
  const Eigen::Matrix3d r = Eigen::AngleAxisd(std::numbers::pi / 4, along).toRotationMatrix();
  return Box(center - r * (size / 2), r, size);
}

// A boss of `radius` rising `height` above the face z = face_z of the part (axis +z, reaching
// kEmbedMm into the material below), with a blind hole of `hole_depth` from its top.
void AddBossWithHole(localize::CadSolid& solid, const Eigen::Vector2d& xy, double face_z,
                     double radius, double height, double hole_diameter, double hole_depth) {
  const Eigen::Matrix3d up = Eigen::Matrix3d::Identity();
  solid.primitives.push_back(
      Cylinder({xy.x(), xy.y(), face_z - kEmbedMm}, up, radius, height + kEmbedMm, false));
  // The hole's tool pokes 1 mm out of the boss top: no coplanar cap.
  solid.primitives.push_back(Cylinder({xy.x(), xy.y(), face_z + height - hole_depth}, up,
                                      hole_diameter / 2, hole_depth + 1.0, true));
}

}  // namespace

void SeatBackOptions::Check(const std::string& what) const {
  Positive(panel_width_mm, what, "panel_width_mm");
  Positive(height_mm, what, "height_mm");
  Positive(thickness_mm, what, "thickness_mm");
  Positive(left_wing_width_mm, what, "left_wing_width_mm");
  Positive(right_wing_width_mm, what, "right_wing_width_mm");
  Positive(ridge_depth_mm, what, "ridge_depth_mm");
  Require(ridge_depth_mm <= thickness_mm - 1, what,
          "ridge_depth_mm must stay 1 mm below thickness_mm (the ridge's lower half lies in the "
          "panel)");
  Positive(grip_boss_radius_mm, what, "grip_boss_radius_mm");
  Positive(grip_boss_height_mm, what, "grip_boss_height_mm");
  Positive(grip_hole_diameter_mm, what, "grip_hole_diameter_mm");
  Positive(grip_hole_depth_mm, what, "grip_hole_depth_mm");
  Positive(mount_boss_radius_mm, what, "mount_boss_radius_mm");
  Positive(mount_boss_height_mm, what, "mount_boss_height_mm");
  Positive(mount_hole_diameter_mm, what, "mount_hole_diameter_mm");
  Positive(mount_hole_depth_mm, what, "mount_hole_depth_mm");
  Require(left_wing_angle_deg > 0 && left_wing_angle_deg <= 60, what,
          "left_wing_angle_deg must be in (0, 60] deg, got " + std::to_string(left_wing_angle_deg));
  Require(
      right_wing_angle_deg > 0 && right_wing_angle_deg <= 60, what,
      "right_wing_angle_deg must be in (0, 60] deg, got " + std::to_string(right_wing_angle_deg));
  Require(right_wing_y_mm.allFinite() && right_wing_y_mm[0] >= 0 &&
              right_wing_y_mm[1] <= height_mm && right_wing_y_mm[1] - right_wing_y_mm[0] > 20,
          what, "right_wing_y_mm must be a range of > 20 mm inside [0, height_mm]");
  Require(thickness_mm > 2 * kEmbedMm && panel_width_mm > 40, what,
          "thickness_mm must exceed 4 mm and panel_width_mm 40 mm");
  const double left_joint = thickness_mm * std::sin(left_wing_angle_deg * kDegToRad) + kEmbedMm;
  const double right_joint = thickness_mm * std::sin(right_wing_angle_deg * kDegToRad) + kEmbedMm;
  Require(left_wing_width_mm > left_joint + 1, what,
          "left_wing_width_mm is too small for the wing's joint");
  Require(right_wing_width_mm > right_joint + 1, what,
          "right_wing_width_mm is too small for the wing's joint");
  const double joint = std::max(left_joint, right_joint);
  const auto boss = [&](const Eigen::Vector2d& xy, double r, double h, double d, double depth,
                        const char* name) {
    Require(xy.allFinite() && std::abs(xy.x()) + r <= panel_width_mm / 2 - joint - 1 &&
                xy.y() - r >= 1 && xy.y() + r <= height_mm - 1,
            what, std::string(name) + "_boss_xy_mm/_radius_mm put the boss off the centre panel");
    Require(d <= 2 * r - 4, what,
            std::string(name) + "_hole_diameter_mm leaves less than a 2 mm wall in the boss");
    Require(depth <= h - 1, what,
            std::string(name) + "_hole_depth_mm must stay 1 mm above the rear face (blind hole)");
    Require(xy.y() + r < ridge_center_y_mm - ridge_depth_mm - 1 ||
                xy.y() - r > ridge_center_y_mm + ridge_depth_mm + 1,
            what, std::string(name) + "_boss_xy_mm puts the boss on the lumbar ridge");
  };
  boss(grip_boss_xy_mm, grip_boss_radius_mm, grip_boss_height_mm, grip_hole_diameter_mm,
       grip_hole_depth_mm, "grip");
  boss(mount_boss_xy_mm, mount_boss_radius_mm, mount_boss_height_mm, mount_hole_diameter_mm,
       mount_hole_depth_mm, "mount");
  Require(
      (grip_boss_xy_mm - mount_boss_xy_mm).norm() > grip_boss_radius_mm + mount_boss_radius_mm + 1,
      what, "grip_boss_xy_mm and mount_boss_xy_mm: the bosses overlap");
  Require(
      ridge_center_y_mm - ridge_depth_mm > 1 && ridge_center_y_mm + ridge_depth_mm < height_mm - 1,
      what, "ridge_center_y_mm/ridge_depth_mm put the ridge off the panel");
}

void ArmrestOptions::Check(const std::string& what) const {
  Positive(post_width_x_mm, what, "post_width_x_mm");
  Positive(post_height_mm, what, "post_height_mm");
  Positive(bar_length_mm, what, "bar_length_mm");
  Positive(bar_back_mm, what, "bar_back_mm");
  Positive(bar_width_y_mm, what, "bar_width_y_mm");
  Positive(bar_thickness_mm, what, "bar_thickness_mm");
  Positive(post_inset_mm, what, "post_inset_mm");
  Positive(pad_length_mm, what, "pad_length_mm");
  Positive(pad_front_inset_mm, what, "pad_front_inset_mm");
  Positive(pad_overhang_mm, what, "pad_overhang_mm");
  Positive(pad_thickness_mm, what, "pad_thickness_mm");
  Positive(boss_radius_mm, what, "boss_radius_mm");
  Positive(boss_height_mm, what, "boss_height_mm");
  Positive(hole_diameter_mm, what, "hole_diameter_mm");
  Require(bar_thickness_mm > 2 * kEmbedMm + 1, what, "bar_thickness_mm must exceed 5 mm");
  Require(bar_back_mm + post_width_x_mm + 1 <= bar_length_mm, what,
          "bar_length_mm must reach past the post's front (bar_back_mm + post_width_x_mm)");
  Require(bar_width_y_mm > 2 * post_inset_mm + 2, what,
          "post_inset_mm leaves no post inside bar_width_y_mm");
  Require(pad_length_mm + pad_front_inset_mm + 1 <= bar_length_mm, what,
          "pad_length_mm + pad_front_inset_mm must stay 1 mm inside bar_length_mm");
  Require(boss_radius_mm <= post_width_x_mm / 2 - 1 && boss_center_z_mm - boss_radius_mm >= 1 &&
              boss_center_z_mm + boss_radius_mm <= post_height_mm - 1,
          what, "boss_radius_mm/boss_center_z_mm put the boss off the post's outer face");
  Require(hole_diameter_mm <= 2 * boss_radius_mm - 4, what,
          "hole_diameter_mm leaves less than a 2 mm wall in the boss");
  Positive(rib_depth_mm, what, "rib_depth_mm");
  Positive(rib_length_mm, what, "rib_length_mm");
  Require(2 * rib_depth_mm <= post_width_x_mm - 4 &&
              rib_depth_mm <= bar_width_y_mm - 2 * post_inset_mm - 1,
          what, "rib_depth_mm does not fit on (and into) the post");
  Require(rib_center_z_mm - rib_length_mm / 2 > boss_center_z_mm + boss_radius_mm + 1 &&
              rib_center_z_mm + rib_length_mm / 2 < post_height_mm - 1,
          what, "rib_center_z_mm/rib_length_mm put the rib off the post or onto the boss");
}

CadChairPart MakeSeatBack(const SeatBackOptions& o) {
  o.Check();
  CadChairPart part;
  part.name = "back";
  const double t = o.thickness_mm, h = o.height_mm;
  const double left_angle = o.left_wing_angle_deg * kDegToRad;
  const double right_angle = o.right_wing_angle_deg * kDegToRad;
  // Each wing's inner end reaches `joint` into the panel, so its end face lies inside it.
  const double left_joint = t * std::sin(left_angle) + kEmbedMm;
  const double right_joint = t * std::sin(right_angle) + kEmbedMm;
  auto& prims = part.solid.primitives;
  prims.push_back(Box({-o.panel_width_mm / 2, 0, 0}, {o.panel_width_mm, h, t}));
  // Right wing: RotY(+angle) turns +x towards -z. Left wing: RotY(-angle) turns +x towards +z,
  // so the wing box runs from its outer end (the corner) inwards to the joint.
  const Eigen::Matrix3d right = RotY(right_angle), left = RotY(-left_angle);
  const Eigen::Vector2d& ry = o.right_wing_y_mm;
  prims.push_back(Box({o.panel_width_mm / 2 - right_joint, ry[0], 0}, right,
                      {o.right_wing_width_mm, ry[1] - ry[0], t}));
  const Eigen::Vector3d left_joint_at(-o.panel_width_mm / 2 + left_joint, 0, 0);
  prims.push_back(
      Box(left_joint_at - o.left_wing_width_mm * left.col(0), left, {o.left_wing_width_mm, h, t}));
  prims.push_back(RoofBar({0, o.ridge_center_y_mm, t}, 0, o.panel_width_mm - 20, o.ridge_depth_mm));
  AddBossWithHole(part.solid, o.grip_boss_xy_mm, t, o.grip_boss_radius_mm, o.grip_boss_height_mm,
                  o.grip_hole_diameter_mm, o.grip_hole_depth_mm);
  AddBossWithHole(part.solid, o.mount_boss_xy_mm, t, o.mount_boss_radius_mm, o.mount_boss_height_mm,
                  o.mount_hole_diameter_mm, o.mount_hole_depth_mm);
  PartGrasp grasp;
  grasp.name = "boss_hole";
  grasp.part_from_grasp.translation() =
      Eigen::Vector3d(o.grip_boss_xy_mm.x(), o.grip_boss_xy_mm.y(), t + o.grip_boss_height_mm);
  grasp.hole_diameter_mm = o.grip_hole_diameter_mm;
  grasp.hole_depth_mm = o.grip_hole_depth_mm;
  part.grasps.push_back(grasp);
  // Front face down (part z up): it rests on the wings' outer front edges.
  part.rest_orientations.push_back(Eigen::Matrix3d::Identity());
  return part;
}

CadChairPart MakeArmrest(const ArmrestOptions& o) {
  o.Check();
  CadChairPart part;
  part.name = "armrest";
  const double in = o.post_inset_mm, bw = o.bar_width_y_mm, bt = o.bar_thickness_mm;
  const double ph = o.post_height_mm, pw = o.post_width_x_mm;
  auto& prims = part.solid.primitives;
  // Post (into the bar by kEmbedMm), bar, pad (kEmbedMm into the bar's top).
  prims.push_back(Box({0, in, 0}, {pw, bw - 2 * in, ph + kEmbedMm}));
  prims.push_back(Box({-o.bar_back_mm, 0, ph}, {o.bar_length_mm, bw, bt}));
  const double pad_x = -o.bar_back_mm + o.bar_length_mm - o.pad_front_inset_mm - o.pad_length_mm;
  prims.push_back(
      Box({pad_x, -o.pad_overhang_mm, ph + bt - kEmbedMm},
          {o.pad_length_mm, bw + 2 * o.pad_overhang_mm, o.pad_thickness_mm + kEmbedMm}));
  // Boss on the post's outer face y = bw - in, axis +y; the hole runs through boss and post
  // (its tool pokes 1 mm out on both sides).
  Eigen::Matrix3d along_y;
  along_y.col(0) = Eigen::Vector3d::UnitX();
  along_y.col(1) = -Eigen::Vector3d::UnitZ();
  along_y.col(2) = Eigen::Vector3d::UnitY();
  const double outer = bw - in;
  prims.push_back(Cylinder({pw / 2, outer - kEmbedMm, o.boss_center_z_mm}, along_y,
                           o.boss_radius_mm, o.boss_height_mm + kEmbedMm, false));
  prims.push_back(RoofBar({pw / 2, outer, o.rib_center_z_mm}, 2, o.rib_length_mm, o.rib_depth_mm));
  const double through = outer + o.boss_height_mm - in;
  prims.push_back(Cylinder({pw / 2, in - 1.0, o.boss_center_z_mm}, along_y, o.hole_diameter_mm / 2,
                           through + 2.0, true));
  PartGrasp grasp;
  grasp.name = "post_hole";
  grasp.part_from_grasp.linear() = along_y;
  grasp.part_from_grasp.translation() =
      Eigen::Vector3d(pw / 2, outer + o.boss_height_mm, o.boss_center_z_mm);
  grasp.hole_diameter_mm = o.hole_diameter_mm;
  grasp.hole_depth_mm = through;
  part.grasps.push_back(grasp);
  // On its inner side (part +y up): the pad's and the post's -y faces towards the deck.
  part.rest_orientations.push_back(
      Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix());
  part.ppf_sampling_step_mm = 10.0;  // Skotheim et al. IV-C: 10 mm voxels for the armrest
  return part;
}

PartGrasp SeatHoleGrasp(const ChairSeat& seat) {
  PartGrasp g;
  g.name = "hole";
  g.part_from_grasp.linear() =
      Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), seat.hole_axis_in_part)
          .toRotationMatrix();
  g.part_from_grasp.translation() = seat.hole_center_in_part;
  g.hole_diameter_mm = 27.0;
  return g;
}

namespace {

localize::GraspFrame GraspFrameOf(const PartGrasp& g, const std::string& where) {
  localize::GraspFrame frame;
  frame.name = g.name;
  frame.part_from_grasp = QuaternionPose::FromIsometry(g.part_from_grasp);
  char mm[32];
  std::snprintf(mm, sizeof(mm), "%g", g.hole_diameter_mm);
  frame.description = "3-finger gripper into the " + std::string(mm) + " mm hole of " + where +
                      ", approach along -z";
  return frame;
}

}  // namespace

localize::PartDefinition SeatPartDefinition(const ChairSeat& seat, const ChairSeat* rendered) {
  localize::PartDefinition part;
  part.name = "seat";
  part.model = "seat.stl";
  part.units = "mm";
  part.grasps.push_back(GraspFrameOf(SeatHoleGrasp(seat), "the boss"));
  // The gripper engages the boss: its position is read from the boss and the shell within
  // 2.5 boss radii (80 mm), where a warp of the moulded shell has not yet built up.
  part.grasps.back().refine_radius_mm = 2.5 * seat.boss_radius_mm;
  if (rendered != nullptr) {
    const double rms = MeasureMeshDeviation(rendered->part.mesh, seat.part.mesh).rms_mm;
    if (rms > 1e-6) part.form_deviation.rms_mm = std::ceil(rms * 100.0) / 100.0;
  }
  return part;
}

localize::PartDefinition CadPartDefinition(const CadChairPart& cad) {
  localize::PartDefinition part;
  part.name = cad.name;
  part.model = cad.name + ".step";
  for (const PartGrasp& g : cad.grasps) {
    part.grasps.push_back(
        GraspFrameOf(g, cad.name == "back" ? "the grip boss" : "the post's boss"));
  }
  if (cad.ppf_sampling_step_mm > 0) part.model_options.sampling_step_mm = cad.ppf_sampling_step_mm;
  for (const Eigen::Matrix3d& cell_from_part : cad.rest_orientations) {
    part.stable_up_in_part.push_back(cell_from_part.transpose() * Eigen::Vector3d::UnitZ());
  }
  return part;
}

MeshPart ReadCadRenderMesh(const std::string& path, double linear_deflection_mm) {
  localize::CadImportOptions options;
  options.linear_deflection_mm = linear_deflection_mm;
  options.angular_deflection_rad = 0.05;
  options.sampling_step_mm = 50.0;  // the samples are not used here
  const localize::CadModel model = localize::ReadCadModel(path, options);
  MeshPart part;
  const std::int32_t patch = part.AddPatch(AnalyticSurface{});
  for (const Eigen::Vector3d& p : model.mesh.vertices.positions) part.AddVertex(p);
  for (const Eigen::Vector3i& f : model.mesh.faces) part.AddFace(f[0], f[1], f[2], patch);
  part.CheckConsistent();
  return part;
}

bool SolidContains(const localize::CadSolid& solid, const Eigen::Vector3d& p_in_part) {
  constexpr double kOnFace = 1e-9;
  bool inside = false;
  for (const localize::CadPrimitive& prim : solid.primitives) {
    const Eigen::Vector3d q = prim.part_from_primitive.inverse() * p_in_part;
    const Eigen::Vector3d& s = prim.size_mm;
    bool in = false;
    if (prim.kind == localize::CadPrimitive::kBox) {
      in = (q.array() >= -kOnFace).all() && (q.array() <= s.array() + kOnFace).all();
    } else {
      in = q.z() >= -kOnFace && q.z() <= s.y() + kOnFace && q.head<2>().norm() <= s.x() + kOnFace;
    }
    if (prim.subtract) {
      inside = inside && !in;
    } else {
      inside = inside || in;
    }
  }
  return inside;
}

}  // namespace lasercell::datasets
