#include "creature_io.h"

#include <png.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <tuple>

namespace creature {

PelageError::PelageError(PelageStatus s, const std::string& what) : std::runtime_error(what), status(s) {}

void check(PelageStatus status, const char* what) {
  if (status != PELAGE_STATUS_OK) {
    throw PelageError(status, std::string(what) + ": " + pelage_status_message(status) + ": " + pelage_last_error());
  }
}

// --- Mesh ------------------------------------------------------------------

PelageMeshDesc Mesh::desc() const {
  PelageMeshDesc d{};
  d.positions = positions.data();
  d.position_stride = 3 * sizeof(float);
  d.vertex_count = vertex_count();
  d.indices = indices.data();
  d.index_stride = 3 * sizeof(uint32_t);
  d.triangle_count = triangle_count();
  d.uvs = uvs.empty() ? nullptr : uvs.data();
  d.uv_stride = 2 * sizeof(float);
  d.normals = normals.empty() ? nullptr : normals.data();
  d.normal_stride = 3 * sizeof(float);
  return d;
}

double Mesh::area(size_t t) const {
  const float* a = &positions[3 * indices[3 * t + 0]];
  const float* b = &positions[3 * indices[3 * t + 1]];
  const float* c = &positions[3 * indices[3 * t + 2]];
  double e1[3], e2[3];
  for (int k = 0; k < 3; ++k) {
    e1[k] = double(b[k]) - a[k];
    e2[k] = double(c[k]) - a[k];
  }
  const double x = e1[1] * e2[2] - e1[2] * e2[1];
  const double y = e1[2] * e2[0] - e1[0] * e2[2];
  const double z = e1[0] * e2[1] - e1[1] * e2[0];
  return 0.5 * std::sqrt(x * x + y * y + z * z);
}

void Mesh::uv_at(size_t t, float u, float v, float out[2]) const {
  const float* a = &uvs[2 * indices[3 * t + 0]];
  const float* b = &uvs[2 * indices[3 * t + 1]];
  const float* c = &uvs[2 * indices[3 * t + 2]];
  for (int k = 0; k < 2; ++k) out[k] = a[k] * (1.0f - u - v) + b[k] * u + c[k] * v;
}

Mesh load_obj(const std::string& path) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = true;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromFile(path, config)) {
    throw std::runtime_error("cannot read " + path + ": " + reader.Error());
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  Mesh mesh;
  std::map<std::tuple<int, int, int>, uint32_t> vertex_of;  // (v, vt, vn) -> vertex
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    for (const tinyobj::index_t& corner : shape.mesh.indices) {
      const auto key = std::make_tuple(corner.vertex_index, corner.texcoord_index, corner.normal_index);
      auto [it, added] = vertex_of.emplace(key, uint32_t(mesh.vertex_count()));
      if (added) {
        for (int k = 0; k < 3; ++k) mesh.positions.push_back(attrib.vertices[3 * size_t(corner.vertex_index) + k]);
        if (corner.texcoord_index >= 0) {
          for (int k = 0; k < 2; ++k) mesh.uvs.push_back(attrib.texcoords[2 * size_t(corner.texcoord_index) + k]);
        }
        if (corner.normal_index >= 0) {
          for (int k = 0; k < 3; ++k) mesh.normals.push_back(attrib.normals[3 * size_t(corner.normal_index) + k]);
        }
      }
      mesh.indices.push_back(it->second);
    }
  }
  // An attribute only some corners have is dropped rather than misaligned.
  if (mesh.uvs.size() != 2 * mesh.vertex_count()) mesh.uvs.clear();
  if (mesh.normals.size() != 3 * mesh.vertex_count()) mesh.normals.clear();
  if (mesh.triangle_count() == 0) throw std::runtime_error(path + ": no triangles");
  return mesh;
}

// --- Images -------------------------------------------------------------------

uint8_t GrayImage::nearest(float u, float v) const {
  const int x = std::clamp(int(std::floor(u * float(width))), 0, width - 1);
  const int y = std::clamp(int(std::floor(v * float(height))), 0, height - 1);
  return at(x, y);
}

float GrayImage::bilinear(float u, float v) const {
  const float fx = std::clamp(u * float(width) - 0.5f, 0.0f, float(width - 1));
  const float fy = std::clamp(v * float(height) - 0.5f, 0.0f, float(height - 1));
  const int x0 = int(fx), y0 = int(fy);
  const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
  const float tx = fx - float(x0), ty = fy - float(y0);
  const float top = at(x0, y0) * (1.0f - tx) + at(x1, y0) * tx;
  const float bottom = at(x0, y1) * (1.0f - tx) + at(x1, y1) * tx;
  return (top * (1.0f - ty) + bottom * ty) / 255.0f;
}

PelageMap GrayImage::map() const {
  PelageMap m{};
  m.kind = PELAGE_MAP_KIND_TEXTURE_U8;
  m.data = texels.data();
  m.width = size_t(width);
  m.height = size_t(height);
  m.stride = size_t(width);
  return m;
}

GrayImage load_png_gray(const std::string& path) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    throw std::runtime_error("cannot read " + path + ": " + image.message);
  }
  image.format = PNG_FORMAT_GRAY;
  GrayImage out;
  out.width = int(image.width);
  out.height = int(image.height);
  out.texels.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.texels.data(), 0, nullptr)) {
    std::string message = image.message;
    png_image_free(&image);
    throw std::runtime_error("cannot decode " + path + ": " + message);
  }
  return out;
}

void write_png_rgb(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = png_uint_32(width);
  image.height = png_uint_32(height);
  image.format = PNG_FORMAT_RGB;
  if (!png_image_write_to_file(&image, path.c_str(), 0, rgb.data(), 0, nullptr)) {
    throw std::runtime_error("cannot write " + path + ": " + image.message);
  }
}

// --- pelage calls -----------------------------------------------------------

std::vector<PelageRoot> stamp(const Mesh& mesh, const PelageStampParams& params, PelageStampInfo* info) {
  const PelageMeshDesc desc = mesh.desc();
  size_t arena_bytes = 0, max_roots = 0;
  check(pelage_stamp_size(&desc, &params, &arena_bytes, &max_roots), "pelage_stamp_size");
  // uninitialised: the stamp writes what it reads, and a host that zeroes a
  // quarter gigabyte first pays for it in page faults
  const std::unique_ptr<unsigned char[]> arena(new unsigned char[arena_bytes]);
  std::vector<PelageRoot> roots(max_roots);
  size_t count = 0;
  check(pelage_stamp(&desc, &params, PelageArena{arena.get(), arena_bytes}, roots.data(), roots.size(), &count, info),
        "pelage_stamp");
  roots.resize(count);
  return roots;
}

void evaluate(const Mesh& mesh, const std::vector<PelageRoot>& roots, std::vector<float>& positions,
              std::vector<float>& normals) {
  const PelageMeshDesc desc = mesh.desc();
  positions.resize(3 * roots.size());
  normals.resize(3 * roots.size());
  check(pelage_roots_evaluate(&desc, roots.data(), roots.size(), positions.data(), 3 * sizeof(float),
                              normals.data(), 3 * sizeof(float)),
        "pelage_roots_evaluate");
}

// --- Strands ---------------------------------------------------------------------

namespace {

// The comb direction projected onto the tangent plane of `n`; where the comb
// is (nearly) parallel to the normal, the world axis least aligned with it.
V3 comb_tangent(V3 n, V3 comb) {
  V3 t = comb - dot(comb, n) * n;
  if (dot(t, t) < 1e-6f) {
    const V3 axes[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    V3 best = axes[0];
    for (const V3& a : axes) {
      if (std::fabs(dot(a, n)) < std::fabs(dot(best, n))) best = a;
    }
    t = best - dot(best, n) * n;
  }
  return normalize(t);
}

}  // namespace

Strands grow_strands(const std::vector<float>& positions, const std::vector<float>& normals,
                     const StrandParams& params) {
  const size_t n = positions.size() / 3;
  Strands s;
  s.control_points.resize(16 * n);
  s.indices.resize(n);
  const float pi = 3.14159265358979f;
  const float a0 = params.tilt_root_deg * pi / 180.0f, a1 = params.tilt_tip_deg * pi / 180.0f;
  const V3 comb{params.comb[0], params.comb[1], params.comb[2]};
  const float length = params.length;
  for (size_t i = 0; i < n; ++i) {
    const V3 p{positions[3 * i], positions[3 * i + 1], positions[3 * i + 2]};
    const V3 nrm = normalize(V3{normals[3 * i], normals[3 * i + 1], normals[3 * i + 2]});
    const V3 t = comb_tangent(nrm, comb);
    const V3 d0 = std::cos(a0) * nrm + std::sin(a0) * t;  // direction at the root
    const V3 d1 = std::cos(a1) * nrm + std::sin(a1) * t;  // direction at the tip
    const V3 chord = normalize(d0 + d1);
    const V3 tip = p + length * chord;
    const V3 cps[4] = {p - length * d0, p, tip, tip + length * d1};
    const float radii[4] = {params.root_radius, params.root_radius, params.tip_radius, params.tip_radius};
    float* out = &s.control_points[16 * i];
    for (int k = 0; k < 4; ++k) {
      out[4 * k + 0] = cps[k].x;
      out[4 * k + 1] = cps[k].y;
      out[4 * k + 2] = cps[k].z;
      out[4 * k + 3] = radii[k];
    }
    s.indices[i] = uint32_t(4 * i);
  }
  return s;
}

size_t count_bad_control_points(const Strands& strands) {
  return count_bad_points(strands.control_points.data(), strands.control_points.size() / 4);
}

size_t count_bad_points(const float* float4, size_t count) {
  size_t bad = 0;
  for (size_t i = 0; i < count; ++i) {
    const float* c = &float4[4 * i];
    const bool finite = std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) && std::isfinite(c[3]);
    if (!finite || c[3] < 0.0f) ++bad;
  }
  return bad;
}

// --- Guide interpolation ---------------------------------------------------

std::vector<float> combed_guides(const Mesh& mesh, const std::vector<PelageRoot>& roots, uint32_t cvs, float length) {
  if (cvs < 2) throw std::runtime_error("combed_guides: a guide needs at least 2 points");
  std::vector<float> positions, normals;
  evaluate(mesh, roots, positions, normals);
  std::vector<float> points(3 * size_t(cvs) * roots.size());
  const float seg = length / float(cvs - 1);
  for (size_t g = 0; g < roots.size(); ++g) {
    const V3 n = at3(normals, g);
    const V3 down = V3{0.0f, -1.0f, 0.0f} - dot(n, V3{0.0f, -1.0f, 0.0f}) * n;
    const float len = creature::length(down);
    const V3 comb = len > 0.0f && std::isfinite(1.0f / len) ? (1.0f / len) * down : V3{};  // zero at the poles
    V3 q = at3(positions, g);
    float* out = &points[3 * size_t(cvs) * g];
    for (uint32_t j = 0; j < cvs; ++j) {
      if (j > 0) {
        const float t = float(j) / float(cvs - 1);
        q = q + seg * normalize((1.0f - 0.6f * t) * n + (0.6f * t) * comb);
      }
      out[3 * j] = q.x, out[3 * j + 1] = q.y, out[3 * j + 2] = q.z;
    }
  }
  return points;
}

PelageGuidesDesc guides_desc(const std::vector<PelageRoot>& roots, const std::vector<float>& points, uint32_t cvs) {
  PelageGuidesDesc d{};
  d.roots = roots.data();
  d.guide_count = roots.size();
  d.points = points.data();
  d.point_stride = 3 * sizeof(float);
  d.point_count = points.size() / 3;
  d.points_per_guide = cvs;
  d.offsets = nullptr;
  return d;
}

std::vector<PelageStrandBinding> bind(const Mesh& mesh, const PelageGuidesDesc& guides, const PelageRoot* strands,
                                      size_t count, const PelageBindParams& params, PelageBindInfo* info) {
  const PelageMeshDesc desc = mesh.desc();
  size_t arena_bytes = 0;
  check(pelage_bind_size(&desc, guides.guide_count, &arena_bytes), "pelage_bind_size");
  std::vector<unsigned char> arena(arena_bytes);
  std::vector<PelageStrandBinding> bindings(count);
  const PelageRestPose rest_pose{&desc, &guides};
  check(pelage_bind(&rest_pose, strands, count, &params, PelageArena{arena.data(), arena.size()}, bindings.data(), bindings.size(), info),
        "pelage_bind");
  return bindings;
}

std::vector<PelageStrandGroom> groom(const Mesh& mesh, const PelageGroomMaps& maps, const PelageRoot* roots,
                                     size_t count) {
  const PelageMeshDesc desc = mesh.desc();
  std::vector<PelageStrandGroom> grooms(count);
  check(pelage_groom_evaluate(&desc, &maps, roots, count, grooms.data(), grooms.size()), "pelage_groom_evaluate");
  return grooms;
}

std::vector<unsigned char> read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path);
  return {std::istreambuf_iterator<char>(in), {}};
}

void write_file(const std::string& path, const unsigned char* data, size_t size) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
  if (!out) throw std::runtime_error("cannot write " + path);
}

std::vector<unsigned char> groom_file(const Mesh& rest, const std::vector<PelageRoot>& guide_roots,
                                      const std::vector<float>& rest_points, uint32_t cvs, uint32_t hairs,
                                      uint32_t patch_size) {
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.target_count = hairs, sp.seed = 2;
  const std::vector<PelageRoot> stamped = stamp(rest, sp);
  const size_t n = stamped.size();
  std::vector<uint32_t> order(n);
  std::vector<PelagePatch> patches((n + patch_size - 1) / patch_size);
  size_t patch_count = 0;
  const PelageMeshDesc rest_desc = rest.desc();
  check(pelage_patch_plan(&rest_desc, stamped.data(), n, patch_size, order.data(), patches.data(), patches.size(),
                          &patch_count),
        "pelage_patch_plan");
  std::vector<PelageRoot> roots(n);
  for (size_t k = 0; k < n; ++k) roots[k] = stamped[order[k]];
  const PelageGuidesDesc rest_guides = guides_desc(guide_roots, rest_points, cvs);
  PelageBindParams bp = pelage_bind_params_defaults();
  bp.run.thread_count = 0;
  const std::vector<PelageStrandBinding> bindings = bind(rest, rest_guides, roots.data(), n, bp);
  PelageGroomMaps maps = pelage_groom_maps_defaults();
  maps.root_width.constant = 0.0016f, maps.tip_width.constant = 0.0003f;
  maps.kink_amplitude.constant = 0.03f, maps.clump.constant = 0.25f, maps.bend.constant = 0.1f;
  const std::vector<PelageStrandGroom> grooms = groom(rest, maps, roots.data(), n);
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = cvs;
  const Frame rest_frame(rest, rest_guides, ep);
  const PelageStrands strands{roots.data(), bindings.data(), grooms.data(), n};
  const PelageGroomFileDesc desc{rest_frame.get(), guide_roots.data(), strands, patches.data(), patch_count};
  size_t bytes = 0;
  pelage_groom_file_write(&desc, nullptr, 0, &bytes);  // CAPACITY_EXCEEDED: the size
  std::vector<unsigned char> file(bytes);
  check(pelage_groom_file_write(&desc, file.data(), file.size(), &bytes), "pelage_groom_file_write");
  file.resize(bytes);
  return file;
}

PelageSettleInfo settle(const Mesh& rest, const PelageGuidesDesc& rest_guides, const PelageRoot* strands,
                        const PelageStrandBinding* bindings, PelageStrandGroom* grooms, size_t count,
                        const PelageExpandParams& params) {
  const PelageMeshDesc desc = rest.desc();
  PelageExpandParams all_cores = params;
  all_cores.run.thread_count = 0;
  size_t bytes = 0;
  check(pelage_settle_size(&desc, rest_guides.guide_count, &all_cores, &bytes), "pelage_settle_size");
  std::vector<unsigned char> arena(bytes);
  PelageSettleInfo info{};
  const PelageRestPose rest_pose{&desc, &rest_guides};
  check(pelage_settle(&rest_pose, strands, bindings, grooms, count, &all_cores, PelageArena{arena.data(), arena.size()}, &info),
        "pelage_settle");
  return info;
}

Frame::Frame(const Mesh& mesh, const PelageGuidesDesc& guides, const PelageExpandParams& params) {
  const PelageMeshDesc desc = mesh.desc();
  check(pelage_frame_new(&desc, guides.guide_count, params.points_per_strand, &frame_), "pelage_frame_new");
  const PelageStatus s = pelage_frame_set_guides(frame_, &guides, params.run);
  if (s != PELAGE_STATUS_OK) {
    pelage_frame_free(frame_);
    check(s, "pelage_frame_set_guides");
  }
}

Expander::Expander(const PelageExpandParams& params) : params_(params) {
  check(pelage_expand_size(&params_, &per_curve_), "pelage_expand_size");
}

void Expander::expand(const Frame& frame, const PelageRoot* strands, const PelageStrandBinding* bindings,
                      const PelageStrandGroom* grooms, size_t count, float* points, size_t capacity,
                      uint32_t* curve_counts, uint32_t* curve_ids) {
  const PelageStrands records{strands, bindings, grooms, count};
  const PelageCurves curves{points, 4 * sizeof(float), capacity, curve_counts, curve_ids};
  check(pelage_expand(frame.get(), &records, &params_, &curves), "pelage_expand");
}

Groom::Groom(const PelageRoot* strands, const PelageStrandBinding* bindings, const PelageStrandGroom* grooms,
             size_t count) {
  const PelageStrands records{strands, bindings, grooms, count};
  check(pelage_groom_new(&records, &groom_), "pelage_groom_new");
}

void Expander::expand(const Frame& frame, const Groom& groom, size_t first, size_t count, float* points,
                      size_t capacity) {
  const PelageCurves curves{points, 4 * sizeof(float), capacity, nullptr, nullptr};
  check(pelage_groom_expand(groom.get(), frame.get(), first, count, &params_, &curves), "pelage_groom_expand");
}

std::vector<uint32_t> segment_indices(size_t curves, size_t per_curve) {
  std::vector<uint32_t> indices(curves * (per_curve >= 3 ? per_curve - 3 : 0));
  check(pelage_curves_segment_indices(curves, per_curve, indices.data(), indices.size()),
        "pelage_curves_segment_indices");
  return indices;
}

// --- Embree -------------------------------------------------------------------

namespace {

const char* rtc_error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE: return "RTC_ERROR_NONE";
    case RTC_ERROR_UNKNOWN: return "RTC_ERROR_UNKNOWN";
    case RTC_ERROR_INVALID_ARGUMENT: return "RTC_ERROR_INVALID_ARGUMENT";
    case RTC_ERROR_INVALID_OPERATION: return "RTC_ERROR_INVALID_OPERATION";
    case RTC_ERROR_OUT_OF_MEMORY: return "RTC_ERROR_OUT_OF_MEMORY";
    case RTC_ERROR_UNSUPPORTED_CPU: return "RTC_ERROR_UNSUPPORTED_CPU";
    case RTC_ERROR_CANCELLED: return "RTC_ERROR_CANCELLED";
  }
  return "unknown RTCError";
}

void record_error(void* user, RTCError code, const char* message) {
  auto* errors = static_cast<std::vector<std::string>*>(user);
  errors->push_back(std::string(rtc_error_name(code)) + ": " + (message ? message : ""));
}

}  // namespace

Device::Device(const char* config) : device(rtcNewDevice(config)) {
  if (!device) throw std::runtime_error(std::string("rtcNewDevice: ") + rtc_error_name(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(device, record_error, &errors);
}

Device::~Device() { rtcReleaseDevice(device); }

void Device::check(const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (!errors.empty() || e != RTC_ERROR_NONE) {
    std::string msg = std::string(what) + ": Embree reported " + rtc_error_name(e);
    for (const std::string& s : errors) msg += "\n  " + s;
    throw std::runtime_error(msg);
  }
}

unsigned attach_mesh(RTCDevice device, RTCScene scene, const Mesh& mesh) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Copied, not shared: Embree reads vertex buffers with 16-byte loads, so a
  // shared float3 buffer would need 4 bytes of padding after its end.
  auto* p = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                        3 * sizeof(float), mesh.vertex_count()));
  auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                           3 * sizeof(uint32_t), mesh.triangle_count()));
  if (p) std::copy(mesh.positions.begin(), mesh.positions.end(), p);
  if (t) std::copy(mesh.indices.begin(), mesh.indices.end(), t);
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

unsigned attach_strands(RTCDevice device, RTCScene scene, const Strands& strands) {
  return attach_curves(device, scene, strands.control_points.data(), strands.control_points.size() / 4,
                       strands.indices.data(), strands.indices.size());
}

unsigned attach_curves(RTCDevice device, RTCScene scene, const float* points, size_t point_count,
                       const uint32_t* indices, size_t segment_count) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, points, 0, 4 * sizeof(float),
                             point_count);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, indices, 0, sizeof(uint32_t),
                             segment_count);
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

// --- Skin coverage -------------------------------------------------------------

std::vector<double> random_root_cdf(const Mesh& mesh, const GrayImage& density, const PelageStampParams& params) {
  std::vector<double> cdf(mesh.triangle_count());
  double total = 0.0;
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    float uv[2];
    mesh.uv_at(t, 1.0f / 3.0f, 1.0f / 3.0f, uv);
    const float d = density.bilinear(uv[0], uv[1]);
    double w = 0.0;
    if (d >= params.bald_below) {
      const double s = params.black_scale + (1.0 - params.black_scale) * std::clamp(d, 0.0f, 1.0f);
      w = mesh.area(t) * s * s;
    }
    total += w;
    cdf[t] = total;
  }
  for (double& c : cdf) c /= total;
  return cdf;
}

std::vector<PelageRoot> random_roots(const std::vector<double>& cdf, size_t count, uint64_t seed) {
  Rng rng{seed};
  std::vector<PelageRoot> roots(count);
  for (size_t i = 0; i < count; ++i) {
    const double x = double(rng.next() >> 11) * (1.0 / 9007199254740992.0);
    const size_t face = size_t(std::upper_bound(cdf.begin(), cdf.end(), x) - cdf.begin());
    const float r = std::sqrt(rng.unit()), b = rng.unit();  // uniform on the triangle
    roots[i] = PelageRoot{uint32_t(std::min(face, cdf.size() - 1)), r * (1.0f - b), r * b, uint32_t(i), uint32_t(i)};
  }
  return roots;
}

RTCRayHit trace(RTCScene scene, V3 org, V3 dir, float tfar) {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh{};
  rh.ray.org_x = org.x, rh.ray.org_y = org.y, rh.ray.org_z = org.z;
  rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
  rh.ray.tnear = 0.0f, rh.ray.tfar = tfar, rh.ray.mask = ~0u;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &ctx, &rh);
  return rh;
}

Coverage::Coverage(const Mesh& m, const GrayImage& d, int r)
    : mesh(m),
      density(d),
      views{{"front", {0, 0, -1}}, {"right", {-1, 0, 0}}, {"back", {0, 0, 1}}, {"left", {1, 0, 0}}},
      resolution(r) {
  V3 lo = at3(m.positions, 0), hi = lo;
  for (size_t i = 1; i < m.vertex_count(); ++i) {
    const V3 p = at3(m.positions, i);
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
  }
  center = 0.5f * (lo + hi);
  half = 1.1f * 0.5f * std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
}

void Coverage::ray(size_t view, int x, int y, V3& org, V3& dir) const {
  const V3 f = views[view].forward;
  const V3 right = normalize(cross(f, V3{0.0f, 1.0f, 0.0f}));
  const V3 up = cross(right, f);
  const float sx = ((float(x) + 0.5f) / float(resolution) * 2.0f - 1.0f) * half;
  const float sy = (1.0f - (float(y) + 0.5f) / float(resolution) * 2.0f) * half;
  org = center + sx * right + sy * up - 5.0f * f;
  dir = f;
}

void Coverage::prepare(RTCScene skin_only) {
  furred.assign(views.size() * rays_per_view(), 0);
  for (size_t v = 0; v < views.size(); ++v) {
    tbb::parallel_for(tbb::blocked_range<int>(0, resolution), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        for (int x = 0; x < resolution; ++x) {
          V3 org, dir;
          ray(v, x, y, org, dir);
          const RTCRayHit h = trace(skin_only, org, dir);
          if (h.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
          float uv[2];
          mesh.uv_at(h.hit.primID, h.hit.u, h.hit.v, uv);
          furred[v * rays_per_view() + size_t(y) * size_t(resolution) + size_t(x)] =
              density.nearest(uv[0], uv[1]) > 0 ? 1 : 0;
        }
      }
    });
  }
  furred_rays = size_t(std::count(furred.begin(), furred.end(), uint8_t(1)));
}

Coverage::Seen Coverage::skin_visible(RTCScene scene, unsigned skin_id) const {
  std::vector<uint8_t> sees_skin(furred.size(), 0);
  for (size_t v = 0; v < views.size(); ++v) {
    tbb::parallel_for(tbb::blocked_range<int>(0, resolution), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y) {
        for (int x = 0; x < resolution; ++x) {
          const size_t i = v * rays_per_view() + size_t(y) * size_t(resolution) + size_t(x);
          if (!furred[i]) continue;
          V3 org, dir;
          ray(v, x, y, org, dir);
          sees_skin[i] = trace(scene, org, dir).hit.geomID == skin_id;
        }
      }
    });
  }
  const size_t visible = size_t(std::count(sees_skin.begin(), sees_skin.end(), uint8_t(1)));
  std::vector<double> share;
  for (size_t v = 0; v < views.size(); ++v) {
    for (int ty = 0; ty + tile <= resolution; ty += tile) {
      for (int tx = 0; tx + tile <= resolution; tx += tile) {
        size_t on_fur = 0, skin = 0;
        for (int y = ty; y < ty + tile; ++y) {
          for (int x = tx; x < tx + tile; ++x) {
            const size_t i = v * rays_per_view() + size_t(y) * size_t(resolution) + size_t(x);
            on_fur += furred[i];
            skin += sees_skin[i];
          }
        }
        if (on_fur == size_t(tile * tile)) share.push_back(double(skin) / double(on_fur));
      }
    }
  }
  std::sort(share.begin(), share.end());
  double worst = 0.0;
  if (!share.empty()) {  // linear between the two nearest ranks, as numpy.percentile
    const double at = 0.99 * double(share.size() - 1);
    const size_t k = size_t(at);
    worst = share[k] + (at - double(k)) * (share[std::min(k + 1, share.size() - 1)] - share[k]);
  }
  const size_t patchy = size_t(share.end() - std::lower_bound(share.begin(), share.end(), 0.25));
  return {double(visible) / double(furred_rays), worst, double(patchy) / double(std::max<size_t>(share.size(), 1)),
          share.size()};
}

}  // namespace creature
