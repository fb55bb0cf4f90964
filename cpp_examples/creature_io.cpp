#include "creature_io.h"

#include <png.h>
#include <tiny_obj_loader.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <tuple>

namespace creature {

PelageError::PelageError(PelageStatus s, const std::string& what) : std::runtime_error(what), status(s) {}

void check(PelageStatus status, const char* what) {
  if (status != PELAGE_STATUS_OK) {
    throw PelageError(status, std::string(what) + ": " + pelage_status_string(status) + ": " + pelage_last_error());
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
  check(pelage_stamp_query(&desc, &params, &arena_bytes, &max_roots), "pelage_stamp_query");
  std::vector<unsigned char> arena(arena_bytes);
  std::vector<PelageRoot> roots(max_roots);
  size_t count = 0;
  check(pelage_stamp(&desc, &params, arena.data(), arena.size(), roots.data(), roots.size(), &count, info),
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

struct V3 {
  float x, y, z;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator*(float s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 normalize(V3 a) { return (1.0f / std::sqrt(dot(a, a))) * a; }

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
  size_t bad = 0;
  for (size_t i = 0; i + 3 < strands.control_points.size(); i += 4) {
    const float* c = &strands.control_points[i];
    const bool finite = std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) && std::isfinite(c[3]);
    if (!finite || c[3] < 0.0f) ++bad;
  }
  return bad;
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
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, strands.control_points.data(), 0,
                             4 * sizeof(float), strands.control_points.size() / 4);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, strands.indices.data(), 0,
                             sizeof(uint32_t), strands.indices.size());
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

}  // namespace creature
