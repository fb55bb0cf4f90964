// embree_interp: guide interpolation on the creature through the C API,
// checked with Embree 3. Stamps ~13K guide roots and 1M render roots, combs
// 16-point guides (all outside the body, checked), binds, grooms (defaults +
// kink and clump) and expands every render hair with pinned ends, then:
//   (a) every hair starts on the surface: point 0 == point 1 == its root, and
//       the root is on the mesh (Embree rays along the root normal);
//   (b) no NaN/Inf coordinate, no negative radius (Embree drops such
//       primitives silently, so we check ourselves);
//   (c) all hairs as one RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE (float4,
//       stride 16, pelage_curves_segment_indices) commit without an Embree
//       error, and are really in the BVH (side rays);
//   (d) after pelage_settle, no control point lies inside the body at the rest pose (ray parity
//       against the body mesh; odd = inside, confirmed along a second
//       direction); the worst cases are printed;
//   (e) skin coverage with interpolated fur: stamped render roots hide more
//       skin than the same number of uniformly random roots, bound and
//       expanded the same way; prints how many random roots match them.
//
//   embree_interp <creature.obj> <creature_density.png> [--roots N] [--guides N]
//                 [--coverage-roots N] [--every K] [--resolution R]
#include "check.h"
#include "creature_io.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace {

using creature::at3;
using creature::V3;

using check::expect;
using check::fmt;

struct Options {
  std::string obj, density;
  uint32_t roots = 1000000;
  uint32_t guides = 13030;
  uint32_t coverage_roots = 200000;
  uint32_t every = 1;  // (d) tests every control point of every `every`-th hair
  int resolution = 512;
};

constexpr uint32_t kCvs = 16;          // guide points
constexpr float kGuideLength = 0.05f;  // guide length

// Crossings of the ray org + t dir (t > 0) with the body: odd = org is inside.
// Hits at the same distance (a shared edge or vertex) count once.
int crossings(RTCScene body, V3 org, V3 dir) {
  int count = 0;
  float tnear = 0.0f;
  for (; count < 256; ++count) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit h{};
    h.ray.org_x = org.x, h.ray.org_y = org.y, h.ray.org_z = org.z;
    h.ray.dir_x = dir.x, h.ray.dir_y = dir.y, h.ray.dir_z = dir.z;
    h.ray.tnear = tnear, h.ray.tfar = 1e30f, h.ray.mask = ~0u;
    h.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(body, &ctx, &h);
    if (h.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
    tnear = std::nextafter(h.ray.tfar * (1.0f + 1e-6f), 1e30f);
  }
  return count;
}

const V3 kParityDir = normalize(V3{0.5271f, 0.7313f, 0.4330f});  // fixed, off every axis
const V3 kConfirmDir = normalize(V3{-0.6167f, -0.3259f, 0.7165f});

// Distance from an inside point to the surface, bounded from above by the
// nearest hit over 26 directions.
float depth_bound(RTCScene body, V3 p) {
  float best = 1e30f;
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if (!x && !y && !z) continue;
        const RTCRayHit h = creature::trace(body, p, normalize(V3{float(x), float(y), float(z)}));
        if (h.hit.geomID != RTC_INVALID_GEOMETRY_ID) best = std::min(best, h.ray.tfar);
      }
    }
  }
  return best;
}

// A control point found inside the body.
struct Inside {
  size_t curve;
  uint32_t point;
  V3 p;
};

struct ParityResult {
  size_t tested = 0;
  size_t odd = 0;                 // odd crossings along kParityDir
  size_t confirmed = 0;           // ... and along kConfirmDir: inside
  std::vector<Inside> inside;     // the confirmed points, by curve and point
  std::vector<Inside> ambiguous;  // the two directions disagree (grazing rays)
};

// Tests points 2 .. per - 2 of every `every`-th of `curves` float4 curves of
// `per` points (0 and 1 are the pinned root, per - 1 repeats the tip).
ParityResult parity(RTCScene body, const float* points, size_t curves, size_t per, size_t every) {
  ParityResult r;
  std::mutex mutex;
  std::atomic<size_t> tested{0}, odd{0};
  const size_t sampled = (curves + every - 1) / every;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, sampled, 256), [&](const tbb::blocked_range<size_t>& range) {
    size_t my_tested = 0, my_odd = 0;
    std::vector<Inside> in, amb;
    for (size_t k = range.begin(); k < range.end(); ++k) {
      const size_t c = k * every;
      for (uint32_t j = 2; j + 1 < per; ++j, ++my_tested) {
        const float* q = &points[4 * (c * per + j)];
        const V3 p{q[0], q[1], q[2]};
        if (crossings(body, p, kParityDir) % 2 == 0) continue;
        ++my_odd;
        (crossings(body, p, kConfirmDir) % 2 ? in : amb).push_back({c, j, p});
      }
    }
    tested += my_tested, odd += my_odd;
    std::lock_guard<std::mutex> lock(mutex);
    r.inside.insert(r.inside.end(), in.begin(), in.end());
    r.ambiguous.insert(r.ambiguous.end(), amb.begin(), amb.end());
  });
  r.tested = tested, r.odd = odd, r.confirmed = r.inside.size();
  auto order = [](const Inside& a, const Inside& b) {
    return a.curve != b.curve ? a.curve < b.curve : a.point < b.point;
  };
  std::sort(r.inside.begin(), r.inside.end(), order);
  std::sort(r.ambiguous.begin(), r.ambiguous.end(), order);
  return r;
}

// Guide points 1 .. cvs - 1 (0 is the root) inside the body: odd crossings
// along either direction (conservative).
bool guide_point_inside(RTCScene body, V3 p) {
  return crossings(body, p, kParityDir) % 2 == 1 || crossings(body, p, kConfirmDir) % 2 == 1;
}

struct GuideCollision {
  size_t points = 0, inside_before = 0, guides_inside = 0, shortened = 0, dropped = 0, inside_after = 0;
  float min_scale = 1.0f;
};

// Keeps the guides out of the body: a guide with a point inside is scaled
// about its root by the largest of 0.95, 0.90, ... 0.05 that puts every
// point outside; one that enters the body right at its root (its root normal
// points inward) is dropped. `shortened` flags the remaining guides that were
// scaled.
GuideCollision keep_guides_outside(RTCScene body, std::vector<PelageRoot>& roots, std::vector<float>& points,
                                   uint32_t cvs, std::vector<uint8_t>& shortened) {
  GuideCollision gc;
  const size_t guides = roots.size();
  std::vector<uint32_t> inside(guides, 0);
  tbb::parallel_for(size_t(0), guides, [&](size_t g) {
    for (uint32_t j = 1; j < cvs; ++j) inside[g] += guide_point_inside(body, at3(points, g * cvs + j));
  });
  std::vector<PelageRoot> kept_roots;
  std::vector<float> kept_points;
  shortened.clear();
  for (size_t g = 0; g < guides; ++g) {
    gc.points += cvs - 1;
    gc.inside_before += inside[g];
    gc.guides_inside += inside[g] > 0;
    const V3 root = at3(points, g * cvs);
    float scale = 1.0f;
    bool outside = inside[g] == 0;
    for (int step = 19; step >= 1 && !outside; --step) {
      scale = 0.05f * float(step);
      outside = true;
      for (uint32_t j = 1; j < cvs && outside; ++j) {
        outside = !guide_point_inside(body, root + scale * (at3(points, g * cvs + j) - root));
      }
    }
    if (!outside) {
      ++gc.dropped;
      continue;
    }
    if (scale < 1.0f) ++gc.shortened, gc.min_scale = std::min(gc.min_scale, scale);
    kept_roots.push_back(roots[g]);
    shortened.push_back(scale < 1.0f);
    for (uint32_t j = 0; j < cvs; ++j) {
      const V3 p = root + scale * (at3(points, g * cvs + j) - root);
      kept_points.insert(kept_points.end(), {p.x, p.y, p.z});
    }
  }
  roots.swap(kept_roots);
  points.swap(kept_points);
  for (size_t i = 1; i < points.size() / 3; ++i) {
    if (i % cvs) gc.inside_after += guide_point_inside(body, at3(points, i));
  }
  return gc;
}

// Guides, bound and groomed render roots, and their expanded curves.
struct Fur {
  std::vector<PelageStrandBinding> bindings;
  std::vector<PelageStrandGroom> grooms;
  std::vector<float> points;  // float4, per_curve per strand
  std::vector<uint32_t> counts, ids;
  PelageBindInfo info{};
  PelageSettleInfo settled{};
  double bind_s = 0, groom_s = 0, settle_s = 0, expand_s = 0;
};

Fur grow(const creature::Mesh& mesh, const PelageGuidesDesc& guides, const std::vector<PelageRoot>& roots,
         const PelageGroomMaps& maps, creature::Expander& expander, bool with_counts) {
  Fur f;
  creature::Stopwatch clock;
  PelageBindParams bind_params = pelage_bind_params_defaults();
  bind_params.run.thread_count = 0;
  f.bindings = creature::bind(mesh, guides, roots.data(), roots.size(), bind_params, &f.info);
  f.bind_s = clock.seconds();
  clock = {};
  f.grooms = creature::groom(mesh, maps, roots.data(), roots.size());
  f.groom_s = clock.seconds();
  clock = {};
  f.settled = creature::settle(mesh, guides, roots.data(), f.bindings.data(), f.grooms.data(), roots.size(),
                               expander.params());
  f.settle_s = clock.seconds();
  const size_t per = expander.points_per_curve();
  f.points.resize(4 * per * roots.size());
  if (with_counts) f.counts.assign(roots.size(), 0xCDCDCDCDu), f.ids.assign(roots.size(), 0xCDCDCDCDu);
  clock = {};
  const creature::Frame frame(mesh, guides, expander.params());
  expander.expand(frame, roots.data(), f.bindings.data(), f.grooms.data(), roots.size(), f.points.data(),
                  per * roots.size(), with_counts ? f.counts.data() : nullptr, with_counts ? f.ids.data() : nullptr);
  f.expand_s = clock.seconds();
  return f;
}

}  // namespace

int main(int argc, char** argv) try {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    auto number = [&] { return uint32_t(std::strtoul(argv[++i], nullptr, 10)); };
    if (!std::strcmp(argv[i], "--roots") && i + 1 < argc) {
      opt.roots = number();
    } else if (!std::strcmp(argv[i], "--guides") && i + 1 < argc) {
      opt.guides = number();
    } else if (!std::strcmp(argv[i], "--coverage-roots") && i + 1 < argc) {
      opt.coverage_roots = number();
    } else if (!std::strcmp(argv[i], "--every") && i + 1 < argc) {
      opt.every = std::max(1u, number());
    } else if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc) {
      opt.resolution = int(number());
    } else if (opt.obj.empty()) {
      opt.obj = argv[i];
    } else if (opt.density.empty()) {
      opt.density = argv[i];
    } else {
      throw std::runtime_error(std::string("unexpected argument ") + argv[i]);
    }
  }
  if (opt.density.empty()) {
    throw std::runtime_error("usage: embree_interp <creature.obj> <creature_density.png> [--roots N] [--guides N] "
                             "[--coverage-roots N] [--every K] [--resolution R]");
  }
  creature::Stopwatch total, clock;
  const creature::Mesh mesh = creature::load_obj(opt.obj);
  const creature::GrayImage density = creature::load_png_gray(opt.density);
  if (mesh.uvs.empty() || mesh.normals.empty()) throw std::runtime_error("the creature needs vt and vn");
  std::printf("creature: %zu vertices, %zu triangles; density %dx%d\n", mesh.vertex_count(), mesh.triangle_count(),
              density.width, density.height);
  creature::Device device;
  RTCScene body = rtcNewScene(device.device);  // the skin alone, for surface and parity queries
  rtcSetSceneFlags(body, RTC_SCENE_FLAG_ROBUST);
  creature::attach_mesh(device.device, body, mesh);
  rtcCommitScene(body);
  device.check("body scene");

  // --- Groom: guides and render roots -----------------------------------------
  clock = {};
  PelageStampParams sp = pelage_stamp_params_defaults();
  sp.density = density.map();
  sp.black_scale = 0.5f;
  sp.target_count = opt.guides, sp.seed = 1;
  std::vector<PelageRoot> guide_roots = creature::stamp(mesh, sp);
  sp.target_count = opt.roots, sp.seed = 2;
  const std::vector<PelageRoot> roots = creature::stamp(mesh, sp);
  const double stamp_s = clock.seconds();
  const size_t n = roots.size();
  std::printf("\nstamp: %zu guide roots (target %u) and %zu render roots (target %u) in %.2f s\n", guide_roots.size(),
              opt.guides, n, opt.roots, stamp_s);

  // Combed guides 0.05 long reach into the narrow gaps between the fingers
  // and beside the ear roots. A groom keeps guides out of the body, so each
  // guide that enters it is shortened (scaled about its root) until it is
  // outside; (d) then measures what interpolation itself adds.
  std::printf("\nguides: %u points, length %.3f, combed toward -y (as tests/src/measure.rs combed_guides)\n", kCvs,
              double(kGuideLength));
  std::vector<float> guide_points = creature::combed_guides(mesh, guide_roots, kCvs, kGuideLength);
  std::vector<uint8_t> shortened;
  {
    clock = {};
    const size_t stamped_guides = guide_roots.size();
    const GuideCollision gc = keep_guides_outside(body, guide_roots, guide_points, kCvs, shortened);
    std::printf("  as combed: %zu of %zu guide points (1..%u) inside the body, in %zu of %zu guides\n",
                gc.inside_before, gc.points, kCvs - 1, gc.guides_inside, stamped_guides);
    std::printf("  kept outside: %zu guides shortened (to %.2f .. 0.95 of their length), %zu dropped (their root "
                "normal points into the body); %zu guides left (%.2f s)\n",
                gc.shortened, double(gc.min_scale), gc.dropped, guide_roots.size(), clock.seconds());
    std::printf("  after: %zu guide points inside the body\n", gc.inside_after);
    expect(gc.inside_after == 0, "every guide lies outside the body (the premise of (d))");
  }
  const PelageGuidesDesc guides = creature::guides_desc(guide_roots, guide_points, kCvs);

  PelageGroomMaps maps = pelage_groom_maps_defaults();
  maps.kink_amplitude.constant = 0.03f;
  maps.kink_frequency.constant = 3.0f;
  maps.clump.constant = 0.25f;
  maps.seed = 7;
  PelageExpandParams ep = pelage_expand_params_defaults();
  ep.points_per_strand = 16;
  ep.end_points = PELAGE_END_POINTS_PINNED;
  ep.orphan_length = kGuideLength;
  ep.run.thread_count = 0;
  creature::Expander expander(ep);
  const size_t per = expander.points_per_curve();
  Fur fur = grow(mesh, guides, roots, maps, expander, true);
  std::printf("\nbind %.2f s (%u orphans of %zu, mean guide length %.4f, spacing %.4f); groom %.3f s; "
              "expand %.3f s (%.2f M hairs/s, %zu points per curve, all cores)\n",
              fur.bind_s, fur.info.orphans, n, double(fur.info.mean_guide_length), double(fur.info.mean_spacing),
              fur.groom_s, fur.expand_s, double(n) / fur.expand_s * 1e-6, per);
  std::printf("settle %.2f s (all cores): %u hairs lifted toward their normal, %u of them unclumped, "
              "%u turned past the normal, %u shortened, %u unresolved\n",
              fur.settle_s, fur.settled.lifted, fur.settled.unclumped, fur.settled.turned, fur.settled.shortened,
              fur.settled.unresolved);
  std::printf("groom: defaults (width %.4f -> %.4f) + kink 0.03 x 3, clump 0.25; expand: 16 points, pinned\n",
              double(pelage_groom_maps_defaults().root_width.constant),
              double(pelage_groom_maps_defaults().tip_width.constant));
  expect(per == 18, fmt("pelage_expand_size: %zu points per pinned 16-point curve", per));
  const float* pts = fur.points.data();

  // --- (a) every hair starts on the surface --------------------------------------
  std::printf("\n(a) hair roots on the surface\n");
  {
    clock = {};
    std::vector<float> positions, normals;
    creature::evaluate(mesh, roots, positions, normals);
    size_t unpinned = 0, off_root = 0, bad_tip = 0, bad_count = 0, bad_id = 0;
    double worst_root = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const float* c = &pts[4 * per * i];
      unpinned += std::memcmp(c, c + 4, 16) != 0;
      bad_tip += std::memcmp(c + 4 * (per - 1), c + 4 * (per - 2), 16) != 0;
      const double d = double(length(V3{c[0], c[1], c[2]} - at3(positions, i)));
      worst_root = std::max(worst_root, d);
      off_root += !(d <= 1e-5);
      bad_count += fur.counts[i] != per;
      bad_id += fur.ids[i] != roots[i].id;
    }
    const float offset = 1e-3f, reach = 2e-3f;
    std::vector<float> hit_t(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
      const float* c = &pts[4 * per * i];
      const V3 p{c[0], c[1], c[2]}, nrm = at3(normals, i);
      RTCRayHit h = creature::trace(body, p + offset * nrm, -1.0f * nrm);  // from outside, inward
      bool hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID && h.ray.tfar <= reach;
      if (!hit) {  // from inside, outward
        h = creature::trace(body, p - offset * nrm, nrm);
        hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID && h.ray.tfar <= reach;
      }
      hit_t[i] = hit ? h.ray.tfar : -1.0f;
    });
    size_t off_surface = 0;
    double worst_dev = 0.0;
    for (size_t i = 0; i < n; ++i) {
      if (hit_t[i] < 0.0f) {
        ++off_surface;
      } else {
        worst_dev = std::max(worst_dev, std::fabs(double(hit_t[i]) - double(offset)));
      }
    }
    std::printf("  point 0 == point 1 (bitwise): %zu of %zu; last == second last: %zu of %zu\n", n - unpinned, n,
                n - bad_tip, n);
    std::printf("  point 0 vs pelage_roots_evaluate: max distance %.2e\n", worst_root);
    std::printf("  rays from root + %.0e n along -n: %zu of %zu hit the body within %.0e; max |t - %.0e| = %.2e\n",
                double(offset), n - off_surface, n, double(reach), double(offset), worst_dev);
    std::printf("  curve_counts all %zu: %zu bad; curve_ids == root ids: %zu bad  (%.2f s)\n", per, bad_count,
                bad_id, clock.seconds());
    expect(unpinned == 0 && bad_tip == 0, "pinned ends: point 0 == point 1 and the tip repeated on every curve");
    expect(off_root == 0, fmt("point 0 is the root (within 1e-5) on every curve (%zu off)", off_root));
    expect(off_surface == 0, fmt("every root is on the mesh within %.0e (%zu off)", double(reach), off_surface));
    expect(bad_count == 0 && bad_id == 0, "curve_counts and curve_ids filled");
  }

  // --- (b) finite, non-negative radius ----------------------------------------------
  std::printf("\n(b) control point values\n");
  {
    size_t non_finite = 0, negative = 0;
    float min_r = 1e30f, max_r = 0.0f;
    for (size_t i = 0; i < per * n; ++i) {
      const float* c = &pts[4 * i];
      const bool finite = std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) && std::isfinite(c[3]);
      non_finite += !finite;
      negative += c[3] < 0.0f;
      if (finite) min_r = std::min(min_r, c[3]), max_r = std::max(max_r, c[3]);
    }
    std::printf("  %zu control points: %zu non-finite, %zu with a negative radius; radius %.5f .. %.5f\n", per * n,
                non_finite, negative, double(min_r), double(max_r));
    expect(non_finite == 0, "no NaN/Inf coordinate or radius");
    expect(negative == 0, "no negative radius");
  }

  // --- (c) one Embree curve geometry with every hair --------------------------------
  std::printf("\n(c) %zu hairs as RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE\n", n);
  {
    clock = {};
    const std::vector<uint32_t> indices = creature::segment_indices(n, per);
    bool indices_ok = indices.size() == n * (per - 3);
    for (size_t s = 0; s < indices.size() && indices_ok; ++s) {
      indices_ok = indices[s] == (s / (per - 3)) * per + s % (per - 3);
    }
    RTCScene scene = rtcNewScene(device.device);
    creature::attach_mesh(device.device, scene, mesh);
    const unsigned fur_id = creature::attach_curves(device.device, scene, pts, per * n, indices.data(), indices.size());
    rtcCommitScene(scene);
    const RTCError err = rtcGetDeviceError(device.device);
    const double bvh_s = clock.seconds();
    RTCBounds b;
    rtcGetSceneBounds(scene, &b);
    // Embree drops bad primitives silently: shoot at the middle of every
    // 500th hair from the side and expect a curve. The skin next to a hair
    // lying on it, or a tight kink (round curves are approximate there), can
    // take one side ray, so four are shot around the hair; a hair missing
    // from the BVH misses all four.
    size_t probes = 0, found = 0, retried = 0;
    for (size_t i = 0; i < n; i += 500, ++probes) {
      const float* c = &pts[4 * per * i];
      const float* m = c + 4 * (per / 2);
      const V3 mid{m[0], m[1], m[2]}, along = normalize(V3{m[4] - m[0], m[5] - m[1], m[6] - m[2]});
      const V3 side = normalize(cross(along, std::fabs(along.x) < 0.9f ? V3{1, 0, 0} : V3{0, 1, 0}));
      const V3 other = cross(along, side);
      const float r = std::max(m[3], 1e-5f);
      int tries = 0;
      for (const V3 d : {side, -1.0f * side, other, -1.0f * other}) {
        ++tries;
        if (creature::trace(scene, mid + 4.0f * r * d, -1.0f * d, 8.0f * r).hit.geomID == fur_id) {
          ++found;
          break;
        }
      }
      retried += tries > 1;
    }
    std::printf("  %zu segments (pelage_curves_segment_indices), %zu float4 points (stride 16); commit %.2f s; "
                "bounds (%.3f %.3f %.3f) .. (%.3f %.3f %.3f)\n",
                indices.size(), per * n, bvh_s, b.lower_x, b.lower_y, b.lower_z, b.upper_x, b.upper_y, b.upper_z);
    std::printf("  side rays at hair midpoints: %zu of %zu hairs hit (%zu needed more than one of 4 directions)\n", found,
                probes, retried);
    expect(indices_ok, "segment indices: curve c, segment s -> c * per + s");
    expect(device.errors.empty(), fmt("no Embree error callback (%zu calls)", device.errors.size()));
    for (const std::string& e : device.errors) std::printf("    Embree: %s\n", e.c_str());
    expect(err == RTC_ERROR_NONE, "rtcGetDeviceError == RTC_ERROR_NONE after commit");
    expect(found == probes, "every probed hair is in the BVH");
    rtcReleaseScene(scene);
  }

  // --- (d) nothing inside the body -------------------------------------------------
  std::printf("\n(d) control points inside the body (rest pose)\n");
  {
    clock = {};
    {
      // The parity test itself: just off the surface along the face normal,
      // every 1000th root is outside on the outside and inside on the inside.
      // As in parity(), a side where the two directions disagree is a ray
      // grazing an edge: not counted, and rare.
      size_t samples = 0, right = 0, grazing = 0;
      for (size_t i = 0; i < n; i += 1000, ++samples) {
        const uint32_t* t = &mesh.indices[3 * size_t(roots[i].face)];
        const V3 a = at3(mesh.positions, t[0]), b = at3(mesh.positions, t[1]), c = at3(mesh.positions, t[2]);
        const V3 nf = normalize(cross(b - a, c - a));
        const float* q = &pts[4 * per * i];
        const V3 p{q[0], q[1], q[2]};
        const auto odd = [&](V3 x) {
          return std::pair{crossings(body, x, kParityDir) % 2, crossings(body, x, kConfirmDir) % 2};
        };
        const auto out = odd(p + 2e-4f * nf), in = odd(p - 2e-4f * nf);
        if (out.first != out.second || in.first != in.second) {
          ++grazing;
          continue;
        }
        right += out.first == 0 && in.first == 1;
      }
      std::printf("  parity check: root +- 2e-4 x face normal classified outside / inside for %zu of %zu roots "
                  "(%zu grazing, not counted)\n",
                  right, samples, grazing);
      expect(right + grazing == samples && grazing <= samples / 100,
             "the parity test tells inside from outside next to the surface");
    }
    const ParityResult pr = parity(body, pts, n, per, opt.every);
    const double parity_s = clock.seconds();
    std::printf("  tested: points 2..%zu (0, 1 are the root, %zu repeats the tip) of %s: %zu points "
                "(%.1f %% of the hairs) in %.2f s\n",
                per - 2, per - 1, opt.every == 1 ? "every hair" : fmt("every %u-th hair", opt.every).c_str(),
                pr.tested, 100.0 / double(opt.every), parity_s);
    std::printf("  odd crossings along (%.3f %.3f %.3f): %zu; also odd along (%.3f %.3f %.3f): %zu (inside); "
                "directions disagree (grazing, not counted): %zu\n",
                double(kParityDir.x), double(kParityDir.y), double(kParityDir.z), pr.odd, double(kConfirmDir.x),
                double(kConfirmDir.y), double(kConfirmDir.z), pr.confirmed, pr.ambiguous.size());

    // One case per hair: its deepest point, and why it might be inside.
    enum Cause { kShortGuide, kRootNormal, kOther, kCauses };
    const char* cause_names[kCauses] = {"using a shortened guide (rooted where combed guides enter the body)",
                                        "whose root normal faces away from its triangle (the mesh's vertex normals)",
                                        "with neither: full-length guides, root normal agrees with its face"};
    struct Case {
      size_t curve;
      uint32_t point, points_inside;
      V3 p, normal;
      float depth, face_dot;
      Cause cause;
    };
    std::vector<Case> cases;
    for (size_t k = 0; k < pr.inside.size();) {
      size_t e = k;
      Case c{pr.inside[k].curve, 0, 0, {}, {}, -1.0f, 0.0f, kOther};
      for (; e < pr.inside.size() && pr.inside[e].curve == c.curve; ++e) {
        const float d = depth_bound(body, pr.inside[e].p);
        ++c.points_inside;
        if (d > c.depth) c.depth = d, c.point = pr.inside[e].point, c.p = pr.inside[e].p;
      }
      const PelageRoot& r = roots[c.curve];
      std::vector<float> rp, rn;
      creature::evaluate(mesh, {r}, rp, rn);
      const uint32_t* t = &mesh.indices[3 * size_t(r.face)];
      const V3 a = at3(mesh.positions, t[0]), b = at3(mesh.positions, t[1]), cc = at3(mesh.positions, t[2]);
      c.normal = at3(rn, 0);
      c.face_dot = dot(c.normal, normalize(cross(b - a, cc - a)));
      const PelageStrandBinding& bd = fur.bindings[c.curve];
      bool short_guide = bd.clump != 0xFFFFFFFFu && shortened[bd.clump];
      for (uint32_t g = 0; g < bd.count; ++g) short_guide |= shortened[bd.guides[g]] != 0;
      c.cause = short_guide ? kShortGuide : c.face_dot < 0.0f ? kRootNormal : kOther;
      cases.push_back(c);
      k = e;
    }
    std::sort(cases.begin(), cases.end(), [](const Case& x, const Case& y) { return x.depth > y.depth; });
    for (int cause = 0; cause < kCauses; ++cause) {
      size_t hairs = 0, points = 0;
      float deepest = 0.0f;
      for (const Case& c : cases) {
        if (c.cause != cause) continue;
        ++hairs, points += c.points_inside, deepest = std::max(deepest, c.depth);
      }
      std::printf("  %6zu hairs %s: %zu points inside, deepest %.2e\n", hairs, cause_names[cause], points,
                  double(deepest));
    }
    for (int cause = 0; cause < kCauses; ++cause) {
      size_t shown = 0;
      for (const Case& c : cases) {
        if (c.cause != cause || shown == 8) continue;
        if (shown++ == 0) {
          std::printf("\n  deepest hairs %s\n  (depth: upper bound, nearest surface hit over 26 directions)\n",
                      cause_names[cause]);
          std::printf("  %8s %6s %8s %8s %3s %4s %9s  %-30s %-27s %6s  %s\n", "hair/id", "face", "u", "v", "pt", "in",
                      "depth", "deepest point", "root normal", "n.face", "guides:weights (clump)");
        }
        const PelageRoot& r = roots[c.curve];
        const PelageStrandBinding& bd = fur.bindings[c.curve];
        std::string gs;
        for (uint32_t g = 0; g < bd.count; ++g) {
          const uint32_t id = bd.guides[g];
          gs += fmt("%s%u%s:%.2f", g ? " " : "", id, shortened[id] ? "*" : "", double(bd.weights[g]));
        }
        std::printf("  %8u %6u %8.5f %8.5f %3u %4u %9.2e  (%8.5f %8.5f %8.5f) (%7.4f %7.4f %7.4f) %6.3f  %s (%u)\n",
                    r.id, r.face, double(r.u), double(r.v), c.point, c.points_inside, double(c.depth), double(c.p.x),
                    double(c.p.y), double(c.p.z), double(c.normal.x), double(c.normal.y), double(c.normal.z),
                    double(c.face_dot), gs.c_str(), bd.clump);
      }
    }
    if (!cases.empty()) std::printf("  (* = a shortened guide)\n");
    if (!pr.ambiguous.empty()) {
      std::printf("  points where the two directions disagree:");
      for (size_t k = 0; k < pr.ambiguous.size() && k < 5; ++k) {
        std::printf(" hair %zu pt %u;", pr.ambiguous[k].curve, pr.ambiguous[k].point);
      }
      std::printf("\n");
    }
    // pelage_settle pushed every strand that entered the body back out
    // (rotation about the root toward the normal, stored as the groom's lift);
    // Embree's parity, along two directions, must agree that nothing is left.
    expect(fur.settled.unresolved == 0, fmt("pelage_settle resolved every strand (%u not)", fur.settled.unresolved));
    expect(pr.confirmed == 0, fmt("no control point inside the body (%zu of %zu, in %zu hairs)", pr.confirmed,
                                  pr.tested, cases.size()));
  }
  fur = Fur{};  // free the 1M curves before (e)

  // --- (e) skin coverage: stamped vs. random render roots -------------------------------
  std::printf("\n(e) skin coverage with interpolated fur\n");
  {
    clock = {};
    creature::Coverage cov(mesh, density, opt.resolution);
    cov.prepare(body);
    sp.target_count = opt.coverage_roots, sp.seed = 2;
    const std::vector<PelageRoot> stamped = creature::stamp(mesh, sp);
    const size_t m = stamped.size();
    struct Row {
      std::string name;
      double multiple;
      size_t count;
      uint32_t orphans;
      creature::Coverage::Seen seen;
    };
    auto measure = [&](const std::string& name, double multiple, const std::vector<PelageRoot>& rs) {
      const Fur f = grow(mesh, guides, rs, maps, expander, false);
      const std::vector<uint32_t> indices = creature::segment_indices(rs.size(), per);
      RTCScene scene = rtcNewScene(device.device);
      const unsigned id = creature::attach_mesh(device.device, scene, mesh);
      creature::attach_curves(device.device, scene, f.points.data(), per * rs.size(), indices.data(), indices.size());
      rtcCommitScene(scene);
      device.check("coverage scene");
      const creature::Coverage::Seen seen = cov.skin_visible(scene, id);
      rtcReleaseScene(scene);
      return Row{name, multiple, rs.size(), f.info.orphans, seen};
    };
    std::vector<Row> rows;
    rows.push_back(measure("pelage stamp (Poisson)", 1.0, stamped));
    const std::vector<double> cdf = creature::random_root_cdf(mesh, density, sp);
    for (double k : {1.0, 1.5, 2.0, 3.0}) {
      const size_t count = size_t(std::llround(k * double(m)));
      rows.push_back(measure(fmt("uniform random, %.1fx", k), k,
                             creature::random_roots(cdf, count, 1000 + uint64_t(10 * k))));
    }
    std::printf("  %zu orthographic views (front, right, back, left) of %dx%d rays; %zu rays hit furred skin "
                "without fur.\n",
                cov.views.size(), cov.resolution, cov.resolution, cov.furred_rays);
    std::printf("  Every set bound to the same %zu guides, groomed and expanded as above (16 points, pinned).\n",
                guide_roots.size());
    std::printf("  Random roots: area x density-scale^2 weighted, bald triangles excluded (pelage's rule); "
                "id = rank = index.\n\n");
    std::printf("  %-26s %10s %8s %14s %14s\n", "render roots", "count", "orphans", "skin visible", "bald patches");
    for (const Row& r : rows) {
      std::printf("  %-26s %10zu %8u %12.2f %% %12.2f %%\n", r.name.c_str(), r.count, r.orphans, 100.0 * r.seen.skin,
                  100.0 * r.seen.patches);
    }
    auto match = [&](double creature::Coverage::Seen::*metric) {
      std::vector<std::pair<double, double>> random;
      for (size_t k = 1; k < rows.size(); ++k) random.emplace_back(rows[k].multiple, rows[k].seen.*metric);
      return check::matching_multiple(rows[0].seen.*metric, random).text();
    };
    std::printf("\n  random roots needed to match stamped: %s (skin visible), %s (bald patches)  (%.1f s)\n",
                match(&creature::Coverage::Seen::skin).c_str(), match(&creature::Coverage::Seen::patches).c_str(),
                clock.seconds());
    expect(rows[0].seen.skin < rows[1].seen.skin,
           fmt("stamped roots show less skin than random roots at equal count (%.2f %% < %.2f %%)",
               100.0 * rows[0].seen.skin, 100.0 * rows[1].seen.skin));
  }

  rtcReleaseScene(body);
  device.check("end");
  std::printf("\nembree_interp: %s (%d failed checks) in %.1f s\n", check::failures ? "FAILED" : "passed", check::failures,
              total.seconds());
  return check::failures ? EXIT_FAILURE : EXIT_SUCCESS;
} catch (const std::exception& e) {
  std::fprintf(stderr, "embree_interp: %s\n", e.what());
  return EXIT_FAILURE;
}
