// Render-time fur (paper 2.1-2.2, 4): a renderer-style procedural that grows
// the fur from files as rays reach it.
//
// 1. The pipeline (once per asset, once per frame) writes the groom file
//    (strands in patch order, the patch table) and one frame's guide cache
//    holding its two shutter samples (open and close).
// 2. The renderer reads only those two files and the frame's deformed mesh
//    at each shutter sample. Each patch is an Embree user primitive whose
//    box, per time step, comes from pelage_patch_boxes; the first ray that
//    enters a box expands that patch (pelage_groom_expand over its strand
//    range, at both samples) into its own motion-blurred sub-scene. Between
//    image buckets, the least recently used patches are evicted once the
//    expanded curves pass a memory cap.
// The same image rendered from all the fur expanded eagerly must match.
//
//   render_lazy <creature.obj> [hairs] [memory cap in MB]
#include <embree3/rtcore.h>
#include <pelage.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "creature_io.h"

using creature::V3;

namespace {

const uint32_t kGuides = 4000, kCvs = 16, kPatchSize = 1000;
// Shutter samples: the creature's lean at shutter open and close.
const int kSamples = 2;
const float kLean[kSamples] = {0.15f, 0.3f};

// The frame's deformed mesh at a shutter sample: the creature leaning
// forward (the renderer gets it from the animation cache; the guides
// follow it).
creature::Mesh deformed(const creature::Mesh& rest, float lean) {
  creature::Mesh m = rest;
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const float y = m.positions[3 * v + 1];
    m.positions[3 * v + 2] += lean * std::max(y, 0.0f) * std::max(y, 0.0f);
  }
  return m;
}

// --- 1. The pipeline: the groom file and one frame's guide cache ----------
void write_files(const creature::Mesh& rest, uint32_t hairs, const std::string& groom_path,
                 const std::string& cache_path) {
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.target_count = kGuides, sp.seed = 1;
  const std::vector<PelageRoot> guide_roots = creature::stamp(rest, sp);
  const std::vector<float> rest_points = creature::combed_guides(rest, guide_roots, kCvs, 0.05f);
  const std::vector<unsigned char> file = creature::groom_file(rest, guide_roots, rest_points, kCvs, hairs, kPatchSize);
  const size_t bytes = file.size();
  creature::write_file(groom_path, file.data(), bytes);
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = kCvs;

  // the frame: at each shutter sample, guides on the deformed mesh (a
  // simulation's output), coded against the groom file's neutral pose
  std::vector<creature::Mesh> posed_mesh;
  std::vector<std::vector<float>> posed_points;
  std::vector<std::unique_ptr<creature::Frame>> frames;
  for (int k = 0; k < kSamples; ++k) {
    posed_mesh.push_back(deformed(rest, kLean[k]));
    posed_points.push_back(creature::combed_guides(posed_mesh[k], guide_roots, kCvs, 0.05f));
  }
  for (int k = 0; k < kSamples; ++k) {
    frames.push_back(std::make_unique<creature::Frame>(
        posed_mesh[k], creature::guides_desc(guide_roots, posed_points[k], kCvs), ep));
  }
  PelageGroomFileInfo info{};
  creature::check(pelage_groom_file_info(file.data(), bytes, &info), "pelage_groom_file_info");
  const size_t n = info.strand_count, patch_count = info.patch_count;
  std::vector<float> guide_local(guide_roots.size() * kCvs * 3);
  std::vector<PelageRoot> r(guide_roots.size()), sr(n);
  std::vector<PelageStrandBinding> sb(n);
  std::vector<PelageStrandGroom> sg(n);
  std::vector<PelagePatch> sp2(patch_count);
  const PelageGroomFileBuffers out{r.data(), guide_local.data(), r.size(), sr.data(), sb.data(), sg.data(), n,
                                   sp2.data(), sp2.size()};
  creature::check(pelage_groom_file_read(file.data(), bytes, &out), "pelage_groom_file_read");
  const PelageGuideSet set{r.data(), guide_local.data(), r.size(), kCvs, info.id};
  size_t most = 0, written = 0;
  creature::check(pelage_guide_cache_size(r.size(), kCvs, kSamples, 0, &most), "pelage_guide_cache_size");
  std::vector<unsigned char> cache(most);
  const PelageFrame samples[kSamples] = {frames[0]->get(), frames[1]->get()};
  creature::check(pelage_guide_cache_write(&set, samples, kSamples, 0, PelageRun{1, nullptr, nullptr}, cache.data(), most, &written),
                  "pelage_guide_cache_write");
  creature::write_file(cache_path, cache.data(), written);
  std::printf("pipeline: %zu hairs in %zu patches; groom file %.1f MB, frame cache (%d samples) %.1f KB (dense: %.1f "
              "MB)\n", n, patch_count, double(bytes) / 1e6, kSamples, double(written) / 1e3,
              double(kSamples) * double(n) * (kCvs + 2) * 16 / 1e6);
}

// --- 2. The renderer --------------------------------------------------------

// What the renderer holds: the groom file's contents, the frame decoded
// from its cache, the patches' boxes.
struct Fur {
  std::vector<PelageRoot> guide_roots, roots;
  std::vector<float> guide_points, boxes;
  std::vector<PelageStrandBinding> bindings;
  std::vector<PelageStrandGroom> grooms;
  std::vector<PelagePatch> patches;
  PelageGroom groom = nullptr;
  PelageFrame frames[kSamples] = {};
  PelageExpandParams params{};
  size_t per = 0;
  ~Fur() {
    pelage_groom_free(groom);
    for (PelageFrame f : frames) pelage_frame_free(f);
  }
};

void load_fur(Fur& fur, const std::string& groom_path, const std::string& cache_path,
              const std::vector<creature::Mesh>& meshes) {
  const std::vector<unsigned char> file = creature::read_file(groom_path), cache = creature::read_file(cache_path);
  PelageGroomFileInfo info{};
  creature::check(pelage_groom_file_info(file.data(), file.size(), &info), "pelage_groom_file_info");
  fur.guide_roots.resize(info.guide_count);
  fur.guide_points.resize(info.guide_count * info.points_per_guide * 3);
  fur.roots.resize(info.strand_count), fur.bindings.resize(info.strand_count), fur.grooms.resize(info.strand_count);
  fur.patches.resize(info.patch_count);
  const PelageGroomFileBuffers out{fur.guide_roots.data(), fur.guide_points.data(), info.guide_count,
                                   fur.roots.data(),       fur.bindings.data(),     fur.grooms.data(),
                                   info.strand_count,      fur.patches.data(),      info.patch_count};
  creature::check(pelage_groom_file_read(file.data(), file.size(), &out), "pelage_groom_file_read");
  const PelageStrands strands{fur.roots.data(), fur.bindings.data(), fur.grooms.data(), info.strand_count};
  creature::check(pelage_groom_new(&strands, &fur.groom), "pelage_groom_new");
  const PelageGuideSet set{fur.guide_roots.data(), fur.guide_points.data(), info.guide_count,
                           info.points_per_guide, info.id};
  fur.params = pelage_expand_params_defaults();
  fur.params.points_per_strand = info.points_per_guide;
  fur.per = fur.params.points_per_strand + 2;  // pinned ends
  fur.params.run.thread_count = 0;
  // a frame per shutter sample, on that sample's mesh; a box per sample
  fur.boxes.resize(6 * kSamples * info.patch_count);
  for (int k = 0; k < kSamples; ++k) {
    const PelageMeshDesc desc = meshes[k].desc();
    creature::check(pelage_frame_new(&desc, info.guide_count, info.points_per_guide, &fur.frames[k]),
                    "pelage_frame_new");
    creature::check(pelage_guide_cache_read(cache.data(), cache.size(), &set, uint32_t(k), fur.frames[k], PelageRun{0, nullptr, nullptr}),
                    "pelage_guide_cache_read");
    creature::check(pelage_patch_boxes(fur.frames[k], &strands, &fur.params, fur.patches.data(), info.patch_count,
                                       &fur.boxes[6 * k * info.patch_count]),
                    "pelage_patch_boxes");
  }
  fur.params.run.thread_count = 1;  // a patch is expanded on the ray's thread
}

// One patch's curves, built the first time a ray enters its box.
struct Patch {
  std::mutex build;
  std::atomic<RTCScene> scene{nullptr};
  std::atomic<int> last_used{-1};
  std::vector<float> points[kSamples];
  std::vector<uint32_t> indices;
  size_t bytes() const { return (kSamples * points[0].size() + indices.size()) * 4; }
};

// Round Catmull-Rom curves moving between the shutter samples: one float4
// buffer (stride 16) per sample, shared with Embree.
void attach_moving_curves(RTCDevice device, RTCScene scene, const std::vector<float>* points, size_t point_count,
                          const std::vector<uint32_t>& indices) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE);
  rtcSetGeometryTimeStepCount(g, kSamples);
  for (int k = 0; k < kSamples; ++k) {
    rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, unsigned(k), RTC_FORMAT_FLOAT4, points[k].data(), 0,
                               16, point_count);
  }
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, indices.data(), 0, sizeof(uint32_t),
                             indices.size());
  rtcCommitGeometry(g);
  rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
}

// The skin moving between the shutter samples.
unsigned attach_moving_mesh(RTCDevice device, RTCScene scene, const std::vector<creature::Mesh>& meshes) {
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryTimeStepCount(g, kSamples);
  for (int k = 0; k < kSamples; ++k) {
    auto* p = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, unsigned(k), RTC_FORMAT_FLOAT3,
                                                          12, meshes[k].vertex_count()));
    if (p) std::copy(meshes[k].positions.begin(), meshes[k].positions.end(), p);
  }
  auto* t = static_cast<uint32_t*>(
      rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, meshes[0].triangle_count()));
  if (t) std::copy(meshes[0].indices.begin(), meshes[0].indices.end(), t);
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

struct Lazy {
  const Fur& fur;
  RTCDevice device;
  std::vector<std::unique_ptr<Patch>> patches;
  std::atomic<size_t> bytes{0}, builds{0}, peak{0}, evictions{0};
  std::atomic<double> build_seconds{0.0};
  std::atomic<bool> failed{false};
  int bucket = 0;

  RTCScene ensure(size_t p) {
    Patch& patch = *patches[p];
    patch.last_used.store(bucket, std::memory_order_relaxed);
    if (RTCScene s = patch.scene.load(std::memory_order_acquire)) return s;
    std::lock_guard<std::mutex> lock(patch.build);
    if (RTCScene s = patch.scene.load(std::memory_order_acquire)) return s;
    creature::Stopwatch clock;
    // Embree's build waits for its own tasks; isolated, the waiting thread
    // cannot take another row whose ray enters this patch (and its lock)
    RTCScene s = nullptr;
    tbb::this_task_arena::isolate([&] { s = build(patch, p); });
    const size_t now = bytes += patch.bytes();
    size_t high = peak.load();
    while (now > high && !peak.compare_exchange_weak(high, now)) {
    }
    builds += 1;
    double seconds = build_seconds.load();
    while (!build_seconds.compare_exchange_weak(seconds, seconds + clock.seconds())) {
    }
    patch.scene.store(s, std::memory_order_release);
    return s;
  }

  // Expands patch `p` at every shutter sample into its own scene.
  RTCScene build(Patch& patch, size_t p) {
    const PelagePatch range = fur.patches[p];
    for (int k = 0; k < kSamples; ++k) {
      patch.points[k].assign(4 * fur.per * range.count, 0.0f);
      const PelageCurves curves{patch.points[k].data(), 16, fur.per * range.count, nullptr, nullptr};
      creature::check(pelage_groom_expand(fur.groom, fur.frames[k], range.first, range.count, &fur.params, &curves),
                      "pelage_groom_expand");
    }
    patch.indices = creature::segment_indices(range.count, fur.per);
    RTCScene s = rtcNewScene(device);
    attach_moving_curves(device, s, patch.points, fur.per * range.count, patch.indices);
    rtcCommitScene(s);
    return s;
  }

  // Between buckets (no ray in flight): the least recently used patches
  // go until the curves fit in `cap` bytes.
  void evict(size_t cap) {
    std::vector<size_t> built;
    for (size_t p = 0; p < patches.size(); ++p) {
      if (patches[p]->scene.load()) built.push_back(p);
    }
    std::sort(built.begin(), built.end(),
              [&](size_t a, size_t b) { return patches[a]->last_used < patches[b]->last_used; });
    for (size_t p : built) {
      if (bytes <= cap) break;
      Patch& patch = *patches[p];
      rtcReleaseScene(patch.scene.exchange(nullptr));
      bytes -= patch.bytes();
      evictions += 1;
      for (auto& points : patch.points) std::vector<float>().swap(points);
      std::vector<uint32_t>().swap(patch.indices);
    }
  }
};

void patch_bounds(const RTCBoundsFunctionArguments* args) {
  const Lazy& lazy = *static_cast<const Lazy*>(args->geometryUserPtr);
  const float* b = &lazy.fur.boxes[6 * (args->timeStep * lazy.fur.patches.size() + args->primID)];
  *args->bounds_o = RTCBounds{b[0], b[1], b[2], 0.0f, b[3], b[4], b[5], 0.0f};
}

// One user geometry holds every patch box (primitive = patch): the first
// ray inside a box builds that patch, then is traced into it.
void patch_intersect(const RTCIntersectFunctionNArguments* args) {
  if (args->N != 1 || !args->valid[0]) return;
  Lazy& lazy = *static_cast<Lazy*>(args->geometryUserPtr);
  RTCRayHit* rh = reinterpret_cast<RTCRayHit*>(args->rayhit);
  // no exception may cross Embree's C callback: a failed patch is recorded
  // and the ray goes on without it
  RTCScene scene = nullptr;
  try {
    scene = lazy.ensure(args->primID);
  } catch (const std::exception&) {
    lazy.failed = true;
    return;
  }
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit sub = *rh;
  sub.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene, &ctx, &sub);
  if (sub.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    rh->ray.tfar = sub.ray.tfar;
    rh->hit = sub.hit;
    rh->hit.geomID = args->geomID;
  }
}

struct View {
  const char* name;
  V3 eye, target;
  float fov_tan;
};

// Headlight shading by the hit normal: skin grey, fur brown.
std::vector<uint8_t> render(RTCScene scene, unsigned mesh_id, const View& v, int size, Lazy* lazy, size_t cap) {
  const V3 forward = normalize(v.target - v.eye);
  const V3 right = normalize(cross(forward, V3{0.0f, 1.0f, 0.0f}));
  const V3 up = cross(right, forward);
  std::vector<uint8_t> rgb(3 * size_t(size) * size_t(size));
  const int bucket_rows = 32;
  for (int y0 = 0; y0 < size; y0 += bucket_rows) {
    tbb::parallel_for(y0, std::min(size, y0 + bucket_rows), [&](int y) {
      for (int x = 0; x < size; ++x) {
        const float sx = (2.0f * (float(x) + 0.5f) / float(size) - 1.0f) * v.fov_tan;
        const float sy = (1.0f - 2.0f * (float(y) + 0.5f) / float(size)) * v.fov_tan;
        const V3 dir = normalize(forward + sx * right + sy * up);
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh{};
        rh.ray.org_x = v.eye.x, rh.ray.org_y = v.eye.y, rh.ray.org_z = v.eye.z;
        rh.ray.dir_x = dir.x, rh.ray.dir_y = dir.y, rh.ray.dir_z = dir.z;
        rh.ray.tfar = 1e30f, rh.ray.mask = ~0u, rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        // a time in the shutter per pixel (a hash: the same in both renders)
        rh.ray.time = float((uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u) % 1024u) / 1023.0f;
        rtcIntersect1(scene, &ctx, &rh);
        V3 c{0.12f, 0.13f, 0.16f};
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
          const V3 ng = normalize(V3{rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z});
          const float l = 0.2f + 0.8f * std::fabs(dot(ng, dir));
          c = rh.hit.geomID == mesh_id ? l * V3{0.55f, 0.5f, 0.48f} : l * V3{0.45f, 0.3f, 0.18f};
        }
        uint8_t* px = &rgb[3 * (size_t(y) * size_t(size) + size_t(x))];
        px[0] = uint8_t(255.0f * std::min(c.x, 1.0f)), px[1] = uint8_t(255.0f * std::min(c.y, 1.0f));
        px[2] = uint8_t(255.0f * std::min(c.z, 1.0f));
      }
    });
    if (lazy) {
      lazy->bucket += 1;
      lazy->evict(cap);
    }
  }
  return rgb;
}

}  // namespace

int main(int argc, char** argv) try {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s creature.obj [hairs] [memory cap MB]\n", argv[0]);
    return 2;
  }
  const uint32_t hairs = argc > 2 ? uint32_t(std::stoul(argv[2])) : 1000000u;
  const size_t cap = size_t(argc > 3 ? std::stod(argv[3]) : 256.0) * 1000000;
  const creature::Mesh rest = creature::load_obj(argv[1]);
  write_files(rest, hairs, "creature.pgroom", "frame.pguide");

  // the renderer: two files and the deformed mesh at each shutter sample
  std::vector<creature::Mesh> meshes;
  for (int k = 0; k < kSamples; ++k) meshes.push_back(deformed(rest, kLean[k]));
  creature::Stopwatch clock;
  Fur fur;
  load_fur(fur, "creature.pgroom", "frame.pguide", meshes);
  const size_t n = fur.roots.size();
  std::printf("renderer: read the groom file and the frame's cache, decoded, %zu patch boxes: %.3f s\n",
              fur.patches.size(), clock.seconds());

  creature::Device device;
  const View views[2] = {{"full", V3{1.6f, 0.8f, 3.6f}, V3{0.0f, 0.05f, 0.0f}, 0.42f},
                         {"face", V3{0.35f, 0.95f, 1.55f}, V3{0.0f, 0.75f, 0.55f}, 0.16f}};
  const int size = 512;
  std::printf("%6s | %8s %7s %9s %8s | %10s %10s | %6s | %s\n", "view", "builds", "patches", "evictions",
              "peak MB", "lazy s", "eager s", "ratio", "pixels differing");
  int failures = 0;
  for (const View& v : views) {
    // eager: every hair expanded at both samples, one BVH
    clock = {};
    std::vector<float> points[kSamples];
    PelageExpandParams ep = fur.params;
    ep.run.thread_count = 0;
    for (int k = 0; k < kSamples; ++k) {
      points[k].resize(4 * fur.per * n);
      const PelageCurves all{points[k].data(), 16, fur.per * n, nullptr, nullptr};
      creature::check(pelage_groom_expand(fur.groom, fur.frames[k], 0, n, &ep, &all), "pelage_groom_expand");
    }
    const double eager_expand_s = clock.seconds();
    const std::vector<uint32_t> indices = creature::segment_indices(n, fur.per);
    RTCScene eager = rtcNewScene(device.device);
    const unsigned eager_mesh = attach_moving_mesh(device.device, eager, meshes);
    attach_moving_curves(device.device, eager, points, fur.per * n, indices);
    rtcCommitScene(eager);
    const double eager_s = clock.seconds();
    const std::vector<uint8_t> want = render(eager, eager_mesh, v, size, nullptr, 0);
    rtcReleaseScene(eager);

    // lazy: patch boxes only, curves when rays come
    Lazy lazy{fur, device.device, {}, {}, {}, {}, {}, {}, {}, 0};
    for (size_t p = 0; p < fur.patches.size(); ++p) lazy.patches.push_back(std::make_unique<Patch>());
    RTCScene scene = rtcNewScene(device.device);
    const unsigned mesh_id = attach_moving_mesh(device.device, scene, meshes);
    RTCGeometry boxes = rtcNewGeometry(device.device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryTimeStepCount(boxes, kSamples);
    rtcSetGeometryUserPrimitiveCount(boxes, unsigned(fur.patches.size()));
    rtcSetGeometryUserData(boxes, &lazy);
    rtcSetGeometryBoundsFunction(boxes, patch_bounds, nullptr);
    rtcSetGeometryIntersectFunction(boxes, patch_intersect);
    rtcCommitGeometry(boxes);
    rtcAttachGeometry(scene, boxes);
    rtcReleaseGeometry(boxes);
    rtcCommitScene(scene);
    device.check("lazy scene");
    const std::vector<uint8_t> got = render(scene, mesh_id, v, size, &lazy, cap);
    const size_t evicted = lazy.evictions.load();
    lazy.evict(0);
    lazy.evictions = evicted;
    rtcReleaseScene(scene);
    device.check("render");

    if (lazy.failed) throw std::runtime_error("a patch failed to expand");
    size_t differing = 0;
    for (size_t i = 0; i < got.size(); i += 3) differing += std::memcmp(&got[i], &want[i], 3) != 0;
    const double lazy_s = lazy.build_seconds.load();
    std::printf("%6s | %8zu %7zu %9zu %8.1f | %10.3f %10.3f | %5.2f | %zu of %d   (eager: expansion %.3f s, BVH "
                "%.3f s)\n", v.name, lazy.builds.load(), fur.patches.size(), lazy.evictions.load(),
                double(lazy.peak.load()) / 1e6, lazy_s, eager_s, lazy_s / eager_s, differing, size * size,
                eager_expand_s, eager_s - eager_expand_s);
    creature::write_png_rgb(std::string("lazy_") + v.name + ".png", size, size, got);
    // the same curves and rays: only ties between hairs at the same depth
    // may resolve differently (a different BVH)
    if (differing > size_t(size) * size_t(size) / 1000) ++failures;
  }
  std::printf("lazy: seconds are expansion + BVH builds of the patches rays reached (summed over threads); eager: "
              "all %zu hairs expanded at %d shutter samples and one motion-blurred BVH built\n", n, kSamples);
  return failures == 0 ? 0 : 1;
} catch (const std::exception& e) {
  std::fprintf(stderr, "render_lazy: %s\n", e.what());
  return 1;
}
