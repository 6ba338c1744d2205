#include "core/html_scene3d.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/html_report.hpp"
#include "core/io/file_util.hpp"

namespace lasercell::report {
namespace {

constexpr const char* kDefaultThreeJs = "/usr/share/javascript/three/three.min.js";

// The bytes of 32-bit values in little-endian order, whatever the host order.
template <typename T>
std::string LittleEndianBytes(const std::vector<T>& values) {
  static_assert(sizeof(T) == 4);
  std::string bytes(values.size() * 4, '\0');
  if (!values.empty()) std::memcpy(bytes.data(), values.data(), bytes.size());
  if constexpr (std::endian::native == std::endian::big) {
    for (std::size_t i = 0; i < bytes.size(); i += 4) {
      std::swap(bytes[i], bytes[i + 3]);
      std::swap(bytes[i + 1], bytes[i + 2]);
    }
  }
  return bytes;
}

nlohmann::json Rgb(const std::array<float, 3>& rgb) { return {rgb[0], rgb[1], rgb[2]}; }

// Column-major 4x4, the order three.js's Matrix4.fromArray reads.
nlohmann::json Matrix(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d m = pose.matrix();
  return std::vector<double>(m.data(), m.data() + 16);
}

void CheckRgb(const std::array<float, 3>& rgb, const std::string& what) {
  for (float c : rgb) {
    if (!(c >= 0.0f && c <= 1.0f)) throw InputError(what + ".rgb: each channel must be in [0, 1]");
  }
}

void CheckPose(const Eigen::Isometry3d& pose, const std::string& what) {
  if (!pose.matrix().allFinite()) throw InputError(what + ": the pose has non-finite entries");
}

std::string Describe(const std::string& title, const char* kind, const std::string& name) {
  return "3D view '" + title + "': " + kind + " '" + name + "'";
}

// Axis-aligned bounds of everything in the scene, in world coordinates.
struct Bounds {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  void Add(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool Empty() const { return !(hi.array() >= lo.array()).all(); }
  Eigen::Vector3d Center() const { return 0.5 * (lo + hi); }
};

Bounds SceneBounds(const Scene3d& scene, const std::vector<std::vector<Eigen::Vector3f>>& kept) {
  Bounds b;
  for (const auto& points : kept) {
    for (const Eigen::Vector3f& p : points) b.Add(p.cast<double>());
  }
  for (const Scene3dMesh& mesh : scene.meshes) {
    for (const Eigen::Vector3f& v : mesh.vertices) b.Add(mesh.world_from_mesh * v.cast<double>());
  }
  for (const Scene3dFrame& frame : scene.frames) {
    b.Add(frame.world_from_frame.translation());
    for (int axis = 0; axis < 3; ++axis) {
      b.Add(frame.world_from_frame * (frame.axis_length_mm * Eigen::Vector3d::Unit(axis)));
    }
  }
  for (const Scene3dBox& box : scene.boxes) {
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p((corner & 1) ? box.max_mm.x() : box.min_mm.x(),
                              (corner & 2) ? box.max_mm.y() : box.min_mm.y(),
                              (corner & 4) ? box.max_mm.z() : box.min_mm.z());
      b.Add(box.world_from_box * p);
    }
  }
  return b;
}

// The view's data: object descriptions with base64 arrays, and the framing sphere.
nlohmann::json SceneJson(const Scene3d& scene) {
  nlohmann::json j;
  j["units"] = scene.units;
  std::vector<std::vector<Eigen::Vector3f>> kept;
  j["points"] = nlohmann::json::array();
  for (const Scene3dPoints& points : scene.points) {
    kept.push_back(DecimatePoints(points.positions, points.max_points));
    std::vector<float> xyz;
    xyz.reserve(3 * kept.back().size());
    for (const Eigen::Vector3f& p : kept.back()) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    j["points"].push_back({{"name", points.name},
                           {"rgb", Rgb(points.rgb)},
                           {"size", points.size_mm},
                           {"count", kept.back().size()},
                           {"total", points.positions.size()},
                           {"positions", Base64(Float32Bytes(xyz))}});
  }
  j["meshes"] = nlohmann::json::array();
  for (const Scene3dMesh& mesh : scene.meshes) {
    std::vector<float> xyz;
    xyz.reserve(3 * mesh.vertices.size());
    for (const Eigen::Vector3f& v : mesh.vertices) xyz.insert(xyz.end(), {v.x(), v.y(), v.z()});
    std::vector<std::uint32_t> indices;
    indices.reserve(3 * mesh.faces.size());
    for (const Eigen::Vector3i& f : mesh.faces) {
      for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(f[k]));
    }
    j["meshes"].push_back({{"name", mesh.name},
                           {"rgb", Rgb(mesh.rgb)},
                           {"opacity", mesh.opacity},
                           {"matrix", Matrix(mesh.world_from_mesh)},
                           {"vertices", Base64(Float32Bytes(xyz))},
                           {"faces", Base64(Uint32Bytes(indices))}});
  }
  j["frames"] = nlohmann::json::array();
  for (const Scene3dFrame& frame : scene.frames) {
    j["frames"].push_back({{"name", frame.name},
                           {"matrix", Matrix(frame.world_from_frame)},
                           {"length", frame.axis_length_mm}});
  }
  j["boxes"] = nlohmann::json::array();
  for (const Scene3dBox& box : scene.boxes) {
    j["boxes"].push_back({{"name", box.name},
                          {"rgb", Rgb(box.rgb)},
                          {"matrix", Matrix(box.world_from_box)},
                          {"min", {box.min_mm.x(), box.min_mm.y(), box.min_mm.z()}},
                          {"max", {box.max_mm.x(), box.max_mm.y(), box.max_mm.z()}}});
  }
  const Bounds bounds = SceneBounds(scene, kept);
  const Eigen::Vector3d center = bounds.Empty() ? Eigen::Vector3d::Zero() : bounds.Center();
  const double radius = bounds.Empty() ? 0.0 : 0.5 * (bounds.hi - bounds.lo).norm();
  j["center"] = {center.x(), center.y(), center.z()};
  j["radius"] = std::max(radius, 1.0);
  return j;
}

// JSON inside <script type="application/json">: '<' only occurs in strings there, where
// \u003c means the same, so no "</script>" can end the element early.
std::string ScriptSafe(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (char c : json) {
    if (c == '<') {
      out += "\\u003c";
    } else {
      out += c;
    }
  }
  return out;
}

// The view code. Draws every .lc-view3d container of the page from its JSON element with
// three.js and its OrbitControls (left drag orbits about the target, z up; right or shift drag
// pans; the wheel zooms; a double click resets the framing), rendering on demand.
const char* const kViewScript = R"JS(
(function () {
  'use strict';
  var FOV = 40, BACKGROUND = 0xf2f3f5;
  var littleEndian = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;
  function decode(b64, Type) {
    var s = atob(b64), bytes = new Uint8Array(s.length);
    for (var i = 0; i < s.length; ++i) bytes[i] = s.charCodeAt(i);
    if (littleEndian) return new Type(bytes.buffer);
    var view = new DataView(bytes.buffer), out = new Type(s.length / 4);
    for (var k = 0; k < out.length; ++k) {
      out[k] = Type === Float32Array ? view.getFloat32(4 * k, true) : view.getUint32(4 * k, true);
    }
    return out;
  }
  function colour(c) { return new THREE.Color(c[0], c[1], c[2]); }
  function posed(object, m) {
    object.matrixAutoUpdate = false;
    object.matrix.fromArray(m);
    return object;
  }
  function geometry(attributes) {
    var g = new THREE.BufferGeometry();
    for (var name in attributes) g.setAttribute(name, attributes[name]);
    return g;
  }
  function pointsObject(p) {
    var g = geometry({position: new THREE.BufferAttribute(decode(p.positions, Float32Array), 3)});
    // three.js scales attenuated points by (canvas height / 2) / depth; dividing by tan(fov / 2)
    // makes `size` the point's extent in scene units.
    var m = new THREE.PointsMaterial({color: colour(p.rgb), sizeAttenuation: true,
                                      size: p.size / Math.tan(FOV * Math.PI / 360)});
    return new THREE.Points(g, m);
  }
  function meshObject(s) {
    var g = geometry({position: new THREE.BufferAttribute(decode(s.vertices, Float32Array), 3)});
    g.setIndex(new THREE.BufferAttribute(decode(s.faces, Uint32Array), 1));
    g = g.toNonIndexed();  // one normal per face: CAD parts have sharp edges
    g.computeVertexNormals();
    var m = new THREE.MeshLambertMaterial({color: colour(s.rgb), side: THREE.DoubleSide,
                                           opacity: s.opacity, transparent: s.opacity < 1});
    return posed(new THREE.Mesh(g, m), s.matrix);
  }
  function label(text, height) {
    var canvas = document.createElement('canvas'), ctx = canvas.getContext('2d');
    var font = '40px sans-serif';
    ctx.font = font;
    canvas.width = Math.ceil(ctx.measureText(text).width) + 8;
    canvas.height = 52;
    ctx.font = font;
    ctx.fillStyle = '#222';
    ctx.textBaseline = 'middle';
    ctx.fillText(text, 4, 26);
    var texture = new THREE.CanvasTexture(canvas);
    texture.minFilter = THREE.LinearFilter;
    var sprite = new THREE.Sprite(new THREE.SpriteMaterial({map: texture, depthTest: false}));
    sprite.center.set(0, 0);
    sprite.scale.set(height * canvas.width / canvas.height, height, 1);
    sprite.renderOrder = 1;
    return sprite;
  }
  // An arrow along +y of `length` from the origin: a shaft and a cone, unlit so that the axis
  // colours stay exact.
  function arrow(length, colour) {
    var material = new THREE.MeshBasicMaterial({color: colour}), head = 0.22 * length;
    var shaft = new THREE.CylinderBufferGeometry(0.025 * length, 0.025 * length, length - head, 8);
    shaft.translate(0, (length - head) / 2, 0);
    var cone = new THREE.ConeBufferGeometry(0.07 * length, head, 12);
    cone.translate(0, length - head / 2, 0);
    var group = new THREE.Group();
    group.add(new THREE.Mesh(shaft, material));
    group.add(new THREE.Mesh(cone, material));
    return group;
  }
  function frameObject(f) {
    var group = new THREE.Group(), L = f.length;
    var x = arrow(L, 0xd62728), y = arrow(L, 0x2ca02c), z = arrow(L, 0x1f5fd6);
    x.rotation.z = -Math.PI / 2;  // +y onto +x
    z.rotation.x = Math.PI / 2;  // +y onto +z
    group.add(x, y, z);
    if (f.name) group.add(label(f.name, 0.25 * L));
    return posed(group, f.matrix);
  }
  function boxObject(b) {
    var xyz = [], lo = b.min, hi = b.max;
    function corner(i) { return [i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]]; }
    for (var i = 0; i < 8; ++i) {
      for (var bit = 1; bit < 8; bit <<= 1) {
        if (!(i & bit)) xyz.push.apply(xyz, corner(i).concat(corner(i | bit)));
      }
    }
    var g = geometry({position: new THREE.Float32BufferAttribute(xyz, 3)});
    return posed(new THREE.LineSegments(g, new THREE.LineBasicMaterial({color: colour(b.rgb)})),
                 b.matrix);
  }
  function hex(c) {
    return '#' + colour(c).getHexString();
  }
  function legend(container, entries, redraw) {
    var box = document.createElement('div');
    box.className = 'lc-view3d-legend';
    entries.forEach(function (e) {
      var row = document.createElement('label'), check = document.createElement('input');
      check.type = 'checkbox';
      check.checked = true;
      check.addEventListener('change', function () { e.object.visible = check.checked; redraw(); });
      var swatch = document.createElement('span');
      swatch.className = 'lc-swatch';
      swatch.style.background = e.colour;
      row.appendChild(check);
      row.appendChild(swatch);
      row.appendChild(document.createTextNode(e.text));
      box.appendChild(row);
    });
    container.appendChild(box);
  }
  function notice(container, text) {
    var p = document.createElement('p');
    p.className = 'lc-view3d-notice';
    p.textContent = text;
    container.appendChild(p);
    container.style.height = 'auto';
  }
  function view(container) {
    var data = JSON.parse(document.getElementById(container.dataset.source).textContent);
    var renderer;
    try {
      renderer = new THREE.WebGLRenderer({antialias: true, preserveDrawingBuffer: true});
    } catch (e) {
      container.dataset.view3dWebgl = '0';
      notice(container, '3D view not shown: this browser provides no WebGL.');
      return;
    }
    var scene = new THREE.Scene(), entries = [];
    function add(object, text, c) {
      scene.add(object);
      entries.push({object: object, text: text, colour: c});
    }
    data.points.forEach(function (p) {
      add(pointsObject(p), p.name + ' (' + p.count + (p.count < p.total ? ' of ' + p.total : '') +
          ' points)', hex(p.rgb));
    });
    data.meshes.forEach(function (m) { add(meshObject(m), m.name, hex(m.rgb)); });
    data.frames.forEach(function (f) { add(frameObject(f), f.name, 'linear-gradient(90deg,#d62728,#2ca02c,#1f5fd6)'); });
    data.boxes.forEach(function (b) { add(boxObject(b), b.name, hex(b.rgb)); });
    scene.add(new THREE.AmbientLight(0xffffff, 0.5));
    var light = new THREE.DirectionalLight(0xffffff, 0.5);
    scene.add(light);
    scene.add(light.target);
    var r = data.radius, camera = new THREE.PerspectiveCamera(FOV, 1, r / 100, r * 100);
    camera.up.set(0, 0, 1);  // cells are z up; OrbitControls keeps camera.up
    var center = new THREE.Vector3().fromArray(data.center);
    // From azimuth -60 deg, elevation 30 deg, far enough to see the bounding sphere.
    camera.position.set(0.433, -0.75, 0.5).multiplyScalar(r / Math.sin(FOV * Math.PI / 360))
        .add(center);
    var controls;
    function draw() {
      var w = container.clientWidth, h = container.clientHeight;
      var size = renderer.getSize(new THREE.Vector2());
      if (size.x !== w || size.y !== h) renderer.setSize(w, h);
      camera.aspect = w / h;
      var distance = camera.position.distanceTo(controls.target);
      camera.near = Math.max(distance - 2 * r, distance / 1000);
      camera.far = distance + 2 * r;
      camera.updateProjectionMatrix();
      light.position.copy(camera.position);
      light.target.position.copy(controls.target);
      renderer.render(scene, camera);
    }
    renderer.setPixelRatio(window.devicePixelRatio || 1);
    renderer.setClearColor(BACKGROUND);
    container.appendChild(renderer.domElement);
    controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.screenSpacePanning = true;
    controls.target.copy(center);
    controls.update();
    controls.saveState();
    controls.addEventListener('change', draw);
    legend(container, entries, draw);
    renderer.domElement.addEventListener('dblclick', function () { controls.reset(); });
    window.addEventListener('resize', draw);
    draw();
    var rect = renderer.domElement.getBoundingClientRect();
    container.dataset.view3dRect = [rect.left + window.scrollX, rect.top + window.scrollY,
                                    rect.width, rect.height].map(Math.round).join(',');
    container.dataset.view3dObjects = String(entries.length);
    container.dataset.view3dDrawn = '1';
  }
  Array.prototype.forEach.call(document.querySelectorAll('div.lc-view3d'), view);
})();
)JS";

// The text of a three.js file for inlining; `marker` must occur in it.
std::string ReadLibrary(const std::string& path, const char* marker) {
  const std::string what = "the three.js file of the report's 3D view";
  const std::string fix =
      ": install libjs-three (scripts/install-deps) or point LASERCELL_THREE_JS at its "
      "three.min.js";
  std::string text;
  try {
    text = io::ReadFileBytes(path);
  } catch (const FileError&) {
    throw FileError(path, "cannot read " + what + fix);
  }
  if (text.find(marker) == std::string::npos) {
    throw FileError(path, "is not " + what + " (no " + marker + " in it)" + fix);
  }
  // Inside <script> only "</script" ends the element; in the library's strings and regular
  // expressions "<\/script" means the same.
  for (std::size_t p = text.find("</script"); p != std::string::npos;
       p = text.find("</script", p)) {
    text.replace(p, 2, "<\\/");
  }
  return text;
}

}  // namespace

void Scene3d::Check() const {
  for (const Scene3dPoints& p : points) {
    const std::string what = Describe(title, "points", p.name);
    if (!(p.size_mm > 0.0f)) throw InputError(what + ".size_mm must be > 0");
    if (p.max_points == 0) throw InputError(what + ".max_points must be > 0");
    CheckRgb(p.rgb, what);
    for (std::size_t i = 0; i < p.positions.size(); ++i) {
      if (!p.positions[i].allFinite()) {
        throw InputError(what + ".positions[" + std::to_string(i) +
                         "] is not finite: drop invalid points first");
      }
    }
  }
  for (const Scene3dMesh& m : meshes) {
    const std::string what = Describe(title, "mesh", m.name);
    if (!(m.opacity > 0.0f && m.opacity <= 1.0f)) throw InputError(what + ".opacity not in (0, 1]");
    CheckRgb(m.rgb, what);
    CheckPose(m.world_from_mesh, what + ".world_from_mesh");
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
      if (!m.vertices[i].allFinite()) {
        throw InputError(what + ".vertices[" + std::to_string(i) + "] is not finite");
      }
    }
    const int n = static_cast<int>(m.vertices.size());
    for (std::size_t i = 0; i < m.faces.size(); ++i) {
      if ((m.faces[i].array() < 0).any() || (m.faces[i].array() >= n).any()) {
        throw InputError(what + ".faces[" + std::to_string(i) +
                         "] has a vertex index outside [0, " + std::to_string(n) + ")");
      }
    }
  }
  for (const Scene3dFrame& f : frames) {
    const std::string what = Describe(title, "frame", f.name);
    if (!(f.axis_length_mm > 0.0f && std::isfinite(f.axis_length_mm))) {
      throw InputError(what + ".axis_length_mm must be > 0");
    }
    CheckPose(f.world_from_frame, what + ".world_from_frame");
  }
  for (const Scene3dBox& b : boxes) {
    const std::string what = Describe(title, "box", b.name);
    CheckRgb(b.rgb, what);
    CheckPose(b.world_from_box, what + ".world_from_box");
    if (!b.min_mm.allFinite() || !b.max_mm.allFinite() ||
        (b.min_mm.array() > b.max_mm.array()).any()) {
      throw InputError(what + ": min_mm must be finite and <= max_mm on every axis");
    }
  }
}

std::vector<Eigen::Vector3f> DecimatePoints(const std::vector<Eigen::Vector3f>& positions,
                                            std::size_t max_points) {
  LASERCELL_CHECK(max_points > 0, "DecimatePoints needs max_points > 0");
  const std::size_t n = positions.size();
  if (n <= max_points) return positions;
  std::vector<Eigen::Vector3f> kept;
  kept.reserve(max_points);
  // floor(i * n / max_points), strictly increasing and < n, without overflowing i * n:
  // i * n = i * q * max_points + i * r with n = q * max_points + r, r < max_points.
  const std::size_t q = n / max_points, r = n % max_points;
  for (std::size_t i = 0; i < max_points; ++i) {
    kept.push_back(positions[i * q + i * r / max_points]);
  }
  return kept;
}

std::string Base64(const std::string& bytes) {
  static const char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint32_t(std::uint8_t(bytes[i])) << 16) |
                            (std::uint32_t(std::uint8_t(bytes[i + 1])) << 8) |
                            std::uint32_t(std::uint8_t(bytes[i + 2]));
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    std::uint32_t v = std::uint32_t(std::uint8_t(bytes[i])) << 16;
    if (rest == 2) v |= std::uint32_t(std::uint8_t(bytes[i + 1])) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += rest == 2 ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string Float32Bytes(const std::vector<float>& values) { return LittleEndianBytes(values); }

std::string Uint32Bytes(const std::vector<std::uint32_t>& values) {
  return LittleEndianBytes(values);
}

std::string OrbitControlsPath(const std::string& three_js_path) {
  const std::size_t slash = three_js_path.rfind('/');
  const std::string folder = slash == std::string::npos ? "." : three_js_path.substr(0, slash);
  return folder + "/examples/js/controls/OrbitControls.js";
}

std::string ThreeJsPath(const std::string& path) {
  if (!path.empty()) return path;
  const char* env = std::getenv("LASERCELL_THREE_JS");
  if (env != nullptr && *env != '\0') return env;
  return kDefaultThreeJs;
}

std::string Scene3dHtml(const Scene3d& scene, int index) {
  scene.Check();
  const std::string id = "lc-view3d-" + std::to_string(index);
  std::size_t shown = 0, total = 0;
  for (const Scene3dPoints& p : scene.points) {
    shown += std::min(p.positions.size(), p.max_points);
    total += p.positions.size();
  }
  std::string s = "<figure class='lc-view3d-figure'>";
  if (!scene.title.empty())
    s += "<div class='lc-view3d-title'>" + EscapeHtml(scene.title) + "</div>";
  s += "<div class='lc-view3d' id='" + id + "' data-view3d='1' data-source='" + id +
       "-data'></div><figcaption>Drag: rotate; right or shift drag: pan; wheel: zoom; double "
       "click: reset. Units: " +
       EscapeHtml(scene.units) + ". " + std::to_string(shown) + " of " + std::to_string(total) +
       " points shown.</figcaption></figure>\n";
  s += "<script type='application/json' id='" + id + "-data'>" +
       ScriptSafe(SceneJson(scene).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)) +
       "</script>\n";
  return s;
}

std::string Scene3dScripts(const std::string& three_js_path) {
  const std::string three = ReadLibrary(three_js_path, "WebGLRenderer");
  const std::string controls = ReadLibrary(OrbitControlsPath(three_js_path), "OrbitControls");
  return "<script>" + three + "\n</script>\n<script>" + controls + "\n</script>\n<script>" +
         kViewScript + "</script>\n";
}

std::string Scene3dStyle() {
  return "<style>.lc-view3d{position:relative;width:100%;height:560px;background:#f2f3f5}"
         ".lc-view3d canvas{display:block}.lc-view3d-title{font-weight:bold;margin:0.3em 0}"
         ".lc-view3d-legend{position:absolute;top:6px;left:6px;background:rgba(255,255,255,0.85);"
         "padding:4px 8px;font-size:12px;max-height:90%;overflow:auto}"
         ".lc-view3d-legend label{display:block;white-space:nowrap}"
         ".lc-swatch{display:inline-block;width:10px;height:10px;margin:0 5px}"
         ".lc-view3d-notice{margin:0;padding:8px;color:#555}</style>\n";
}

}  // namespace lasercell::report
