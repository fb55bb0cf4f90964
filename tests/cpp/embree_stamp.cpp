// embree_stamp: stamps roots on a mesh (the creature) through the C API, at
// one or more counts, and checks each set with Embree 3:
//   (a) every root lies on the mesh surface (rays along the root normal),
//   (b) no root lies in the bald regions of the density map (needs a map),
//   (c) straight strands grown from the roots are valid Embree round
//       Catmull-Rom curves (error callback, rtcGetDeviceError, our own
//       NaN/Inf/negative-radius check, and rays that find the curves),
//   (d) skin coverage against uniformly random roots at 1x to 2.5x the count:
//       the mean share of furred-skin rays that see skin, and the worst
//       patches (99th percentile of that share over 16x16-ray tiles), each
//       with its random-equivalent (issue 30): how many random roots, as a
//       multiple, leave as much skin visible as the stamped ones,
//   (e) spacing: nearest same-side neighbours, stamped vs. random.
//
//   embree_stamp <mesh.obj> [<density.png>] [--roots N[,N...]] [--resolution R]
//                [--length L] [--radius R] [--tilt DEGREES]   (strands; defaults 0.06, 0.0015, 60)
//                [--relative] [--min-mean-multiple X] [--min-p99-multiple Y] [--reference PREFIX]
//                [--seed S]
//
// Without a density map the density is constant 1 (pelage's default) and (b)
// is skipped. The --min-*-multiple options fail the run when a count's
// random-equivalent falls below them; without them (d) only checks that
// stamped roots beat random ones at equal count. --reference names the
// reference roots of each count, `PREFIX_<count>.bin` (PelageRoot records,
// little-endian, as `make_darts` writes a plain dart-throwing Poisson set of
// the same count): (d) measures them too, and the stamp's random-equivalents
// must come within 0.05x (mean) and 0.15x (worst patches, a percentile
// that moves by 0.12x between stamp seeds) of theirs. --relative makes
// --length and --radius multiples of each count's disk radius; --seed sets
// the stamp's seed (1).
#include "check.h"
#include "creature_io.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstdarg>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

namespace {

using check::expect;
using check::fmt;

using creature::at3;
using creature::Coverage;
using creature::V3;
using creature::random_root_cdf;
using creature::random_roots;
using creature::trace;

// Random root counts for (d), as multiples of the stamped count: a bracket
// around the stamped roots' coverage, fine enough near issue 30's targets
// (1.35x mean, 1.5x worst patches) to interpolate.
constexpr double kMultiples[] = {1.0, 1.25, 1.5, 1.75, 2.0, 2.5};

// Distance from each root to its nearest neighbour on the same side of the
// surface (face normals not opposed, pelage's rule), searched up to `reach`
// (roots with no neighbour that close report `reach`).
std::vector<float> nearest_neighbours(const creature::Mesh& mesh, const std::vector<PelageRoot>& roots,
                                      const std::vector<float>& positions, float reach) {
  const size_t n = roots.size();
  std::vector<V3> face_normal(n);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t* t = &mesh.indices[3 * size_t(roots[i].face)];
    const V3 a = at3(mesh.positions, t[0]), b = at3(mesh.positions, t[1]), c = at3(mesh.positions, t[2]);
    face_normal[i] = normalize(cross(b - a, c - a));
  }
  // A hash grid with cells of side `reach`.
  auto cell = [&](V3 p, int d[3]) {
    d[0] = int(std::floor(p.x / reach)), d[1] = int(std::floor(p.y / reach)), d[2] = int(std::floor(p.z / reach));
  };
  auto hash = [](int x, int y, int z, size_t buckets) {
    return (uint64_t(uint32_t(x)) * 73856093u ^ uint64_t(uint32_t(y)) * 19349663u ^ uint64_t(uint32_t(z)) * 83492791u) %
           buckets;
  };
  const size_t buckets = 2 * n + 1;
  std::vector<uint32_t> start(buckets + 1, 0), items(n);
  std::vector<size_t> bucket_of(n);
  for (size_t i = 0; i < n; ++i) {
    int d[3];
    cell(at3(positions, i), d);
    bucket_of[i] = size_t(hash(d[0], d[1], d[2], buckets));
    ++start[bucket_of[i] + 1];
  }
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<uint32_t> fill(start.begin(), start.end() - 1);
  for (size_t i = 0; i < n; ++i) items[fill[bucket_of[i]]++] = uint32_t(i);
  std::vector<float> nn(n, reach);
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const V3 p = at3(positions, i);
    int d[3];
    cell(p, d);
    float best = reach;
    for (int dz = -1; dz <= 1; ++dz) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const size_t b = size_t(hash(d[0] + dx, d[1] + dy, d[2] + dz, buckets));
          for (uint32_t k = start[b]; k < start[b + 1]; ++k) {
            const uint32_t j = items[k];
            if (j == i || dot(face_normal[i], face_normal[j]) <= 0.0f) continue;
            best = std::min(best, length(at3(positions, j) - p));
          }
        }
      }
    }
    nn[i] = best;
  });
  return nn;
}

struct Options {
  std::string obj, density;  // no density: constant 1
  std::vector<uint32_t> roots{100000};
  int resolution = 512;
  creature::StrandParams strands;  // 0.06 long, radius 0.0015, 60 degrees toward world -y
  std::optional<double> min_mean_multiple, min_p99_multiple;
  // Reference roots per count, `<reference>_<count>.bin` (make_darts):
  // measured beside the stamp, which must cover the skin about as well.
  std::string reference;
  // --length and --radius as multiples of each count's disk radius (fur as
  // short as the roots are apart: where their spacing shows most)
  bool relative = false;
  // the stamp's seed (the reference and the random roots keep theirs)
  uint64_t seed = 1;
};

const char* const kUsage =
    "usage: embree_stamp <mesh.obj> [<density.png>] [--roots N[,N...]] [--resolution R] [--length L] "
    "[--radius R] [--tilt DEGREES] [--relative] [--min-mean-multiple X] [--min-p99-multiple Y] [--reference PREFIX] [--seed S]";

std::vector<uint32_t> parse_counts(const std::string& list) {
  std::vector<uint32_t> counts;
  const char* p = list.c_str();
  for (;;) {
    char* end = nullptr;
    const unsigned long n = std::strtoul(p, &end, 10);
    if (end == p || n == 0 || n > 0xFFFFFFFFul || (*end != ',' && *end != '\0')) {
      throw std::runtime_error("--roots takes positive counts separated by commas, not " + list);
    }
    counts.push_back(uint32_t(n));
    if (*end == '\0') return counts;
    p = end + 1;
  }
}

// A minimum multiple is only decidable inside the measured bracket.
double parse_multiple(const char* name, const char* value) {
  char* end = nullptr;
  const double m = std::strtod(value, &end);
  if (end == value || *end != '\0' || !(m >= kMultiples[0] && m <= std::end(kMultiples)[-1])) {
    throw std::runtime_error(fmt("%s takes a multiple between %.2f and %.2f (the random roots measured), not %s",
                                 name, kMultiples[0], std::end(kMultiples)[-1], value));
  }
  return m;
}

Options parse(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--roots") && i + 1 < argc) {
      opt.roots = parse_counts(argv[++i]);
    } else if (!std::strcmp(argv[i], "--resolution") && i + 1 < argc) {
      opt.resolution = std::atoi(argv[++i]);
    } else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) {
      opt.seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (!std::strcmp(argv[i], "--relative")) {
      opt.relative = true;
    } else if (!std::strcmp(argv[i], "--reference") && i + 1 < argc) {
      opt.reference = argv[++i];
    } else if (!std::strcmp(argv[i], "--length") && i + 1 < argc) {
      opt.strands.length = std::strtof(argv[++i], nullptr);
    } else if (!std::strcmp(argv[i], "--radius") && i + 1 < argc) {
      opt.strands.root_radius = opt.strands.tip_radius = std::strtof(argv[++i], nullptr);
    } else if (!std::strcmp(argv[i], "--tilt") && i + 1 < argc) {
      opt.strands.tilt_root_deg = opt.strands.tilt_tip_deg = std::strtof(argv[++i], nullptr);
    } else if (!std::strcmp(argv[i], "--min-mean-multiple") && i + 1 < argc) {
      opt.min_mean_multiple = parse_multiple(argv[i], argv[i + 1]), ++i;
    } else if (!std::strcmp(argv[i], "--min-p99-multiple") && i + 1 < argc) {
      opt.min_p99_multiple = parse_multiple(argv[i], argv[i + 1]), ++i;
    } else if (argv[i][0] == '-') {
      throw std::runtime_error(std::string("unknown option ") + argv[i] + "\n" + kUsage);
    } else if (opt.obj.empty()) {
      opt.obj = argv[i];
    } else if (opt.density.empty()) {
      opt.density = argv[i];
    } else {
      throw std::runtime_error(std::string("unexpected argument ") + argv[i] + "\n" + kUsage);
    }
  }
  if (opt.obj.empty()) throw std::runtime_error(kUsage);
  return opt;
}

// --- (a) every root lies on the surface ----------------------------------
void on_surface(creature::Device& device, const creature::Mesh& mesh, const std::vector<PelageRoot>& roots,
                const std::vector<float>& positions, const std::vector<float>& normals) {
  std::printf("\n(a) roots on the surface\n");
  const size_t n = roots.size();
  RTCScene skin = rtcNewScene(device.device);
  creature::attach_mesh(device.device, skin, mesh);
  rtcCommitScene(skin);
  device.check("skin scene");
  const float offset = 1e-3f, reach = 2e-3f;
  std::vector<float> hit_t(n);
  std::vector<uint8_t> same_face(n), ok(n);
  double worst_eval = 0.0;
  for (size_t i = 0; i < n; ++i) {  // pelage's evaluation against our own
    const uint32_t* t = &mesh.indices[3 * size_t(roots[i].face)];
    const float u = roots[i].u, v = roots[i].v;
    const V3 ref = (1.0f - u - v) * at3(mesh.positions, t[0]) + u * at3(mesh.positions, t[1]) +
                   v * at3(mesh.positions, t[2]);
    worst_eval = std::max(worst_eval, double(length(at3(positions, i) - ref)));
  }
  tbb::parallel_for(size_t(0), n, [&](size_t i) {
    const V3 p = at3(positions, i), nrm = at3(normals, i);
    RTCRayHit h = trace(skin, p + offset * nrm, -1.0f * nrm);  // from outside, inward
    bool hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID && h.ray.tfar <= reach;
    if (!hit) {  // from inside, outward (a normal that points the wrong way)
      h = trace(skin, p - offset * nrm, nrm);
      hit = h.hit.geomID != RTC_INVALID_GEOMETRY_ID && h.ray.tfar <= reach;
    }
    hit_t[i] = hit ? h.ray.tfar : -1.0f;
    same_face[i] = hit && h.hit.primID == roots[i].face;
    ok[i] = hit;
  });
  size_t failures = 0, same = 0;
  double worst_dev = 0.0;
  for (size_t i = 0; i < n; ++i) {
    failures += !ok[i];
    same += same_face[i];
    if (ok[i]) worst_dev = std::max(worst_dev, std::fabs(double(hit_t[i]) - offset));
  }
  std::printf("  pelage_roots_evaluate vs. barycentric interpolation here: max difference %.2e\n", worst_eval);
  std::printf("  rays from p + %.0e n along -n: %zu of %zu hit within %.0e; max |t - %.0e| = %.2e; "
              "%.2f %% hit the root's own triangle\n",
              double(offset), n - failures, n, double(reach), double(offset), worst_dev, 100.0 * same / double(n));
  expect(worst_eval < 1e-5, "evaluated positions match (1 - u - v) p0 + u p1 + v p2");
  expect(failures == 0, fmt("every root is on the surface (%zu off)", failures));
  rtcReleaseScene(skin);
}

// --- (b) no roots in bald regions ---------------------------------------
void bald_regions(const creature::Mesh& mesh, const creature::GrayImage& density, const std::vector<PelageRoot>& roots,
                  float bald_below) {
  std::printf("\n(b) bald regions (density 0: face and palms)\n");
  const size_t n = roots.size();
  // "Deep" bald texels: black, and every texel within +-20 columns and
  // +-10 rows is black too (wider than any triangle near the bald discs).
  const int rx = 20, ry = 10, w = density.width, h = density.height;
  std::vector<uint8_t> rowmax(size_t(w) * size_t(h)), deep(size_t(w) * size_t(h));
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t m = 0;
      for (int k = std::max(0, x - rx); k <= std::min(w - 1, x + rx); ++k) m = std::max(m, density.at(k, y));
      rowmax[size_t(y) * size_t(w) + size_t(x)] = m;
    }
  }
  size_t deep_texels = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t m = 0;
      for (int k = std::max(0, y - ry); k <= std::min(h - 1, y + ry); ++k) {
        m = std::max(m, rowmax[size_t(k) * size_t(w) + size_t(x)]);
      }
      deep[size_t(y) * size_t(w) + size_t(x)] = m == 0;
      deep_texels += m == 0;
    }
  }
  size_t black_texels = size_t(std::count(density.texels.begin(), density.texels.end(), uint8_t(0)));
  size_t on_black = 0, on_deep = 0, on_bald_triangle = 0;
  for (size_t i = 0; i < n; ++i) {
    float uv[2], c[2];
    mesh.uv_at(roots[i].face, roots[i].u, roots[i].v, uv);
    mesh.uv_at(roots[i].face, 1.0f / 3.0f, 1.0f / 3.0f, c);
    const int x = std::clamp(int(uv[0] * float(w)), 0, w - 1), y = std::clamp(int(uv[1] * float(h)), 0, h - 1);
    on_black += density.at(x, y) == 0;
    on_deep += deep[size_t(y) * size_t(w) + size_t(x)];
    on_bald_triangle += density.bilinear(c[0], c[1]) < bald_below;
  }
  std::printf("  texels: %zu black, %zu deep inside the black regions\n", black_texels, deep_texels);
  std::printf("  roots whose triangle's centroid density is below bald_below (%.5f): %zu\n", double(bald_below),
              on_bald_triangle);
  std::printf("  roots on a black texel: %zu (%.3f %%); deep inside a bald region: %zu\n", on_black,
              100.0 * on_black / double(n), on_deep);
  expect(deep_texels > 0, "the density map has bald regions");
  expect(on_bald_triangle == 0, "no roots on triangles whose centroid density is below bald_below");
  expect(on_deep == 0, "no roots deep inside bald regions");
  expect(on_black < 0.005 * double(n), "fewer than 0.5 % of the roots on black texels (region borders)");
}

// --- (c) strands as Embree curves ----------------------------------------
void curves(creature::Device& device, const creature::Mesh& mesh, const creature::Strands& strands,
            const creature::StrandParams& sp) {
  std::printf("\n(c) straight strands as RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE\n");
  const size_t bad = creature::count_bad_control_points(strands);
  bool indices_ok = true;
  for (size_t i = 0; i < strands.count(); ++i) indices_ok &= strands.indices[i] + 3 < strands.control_points.size() / 4;
  RTCScene scene = rtcNewScene(device.device);
  creature::attach_mesh(device.device, scene, mesh);
  creature::attach_strands(device.device, scene, strands);
  rtcCommitScene(scene);
  const RTCError err = rtcGetDeviceError(device.device);
  RTCBounds b;
  rtcGetSceneBounds(scene, &b);
  std::printf("  %zu curves, %zu control points (float4, stride 16); scene bounds (%.3f %.3f %.3f) .. "
              "(%.3f %.3f %.3f)\n",
              strands.count(), strands.control_points.size() / 4, b.lower_x, b.lower_y, b.lower_z, b.upper_x,
              b.upper_y, b.upper_z);
  expect(bad == 0, fmt("control points finite with radius >= 0 (%zu bad)", bad));
  expect(indices_ok, "every index points at the first of 4 control points in range");
  expect(device.errors.empty(), fmt("no Embree error callback (%zu calls)", device.errors.size()));
  for (const std::string& e : device.errors) std::printf("    Embree: %s\n", e.c_str());
  expect(err == RTC_ERROR_NONE, "rtcGetDeviceError == RTC_ERROR_NONE after commit");

  // Embree drops bad primitives silently: check that the curves are really
  // there by shooting at the middle of every 50th strand from the side
  // (curves only: near the thin ears the skin can be closer than 4 radii).
  RTCScene fur = rtcNewScene(device.device);
  const unsigned fur_id = creature::attach_strands(device.device, fur, strands);
  rtcCommitScene(fur);
  size_t probes = 0, found = 0, own = 0;
  for (size_t i = 0; i < strands.count(); i += 50, ++probes) {
    const float* c = &strands.control_points[16 * i];
    const V3 root{c[4], c[5], c[6]}, tip{c[8], c[9], c[10]};
    const V3 along = normalize(tip - root);
    const V3 side = normalize(cross(along, std::fabs(along.x) < 0.9f ? V3{1, 0, 0} : V3{0, 1, 0}));
    const V3 mid = 0.5f * (root + tip);
    const RTCRayHit h = trace(fur, mid + 4.0f * sp.root_radius * side, -1.0f * side, 8.0f * sp.root_radius);
    found += h.hit.geomID == fur_id;
    own += h.hit.geomID == fur_id && h.hit.primID == i;
  }
  std::printf("  side rays at strand midpoints: %zu of %zu hit a curve, %zu the strand aimed at\n", found, probes, own);
  expect(found == probes, "every probed strand is in the BVH");
  rtcReleaseScene(fur);
  rtcReleaseScene(scene);
  device.check("curves");
}

// --- (d) skin coverage: stamped vs. random roots -------------------------
// The reference roots of `count` from `PREFIX_<count>.bin` (see the top).
std::vector<PelageRoot> load_reference(const std::string& prefix, size_t count, size_t triangles) {
  const std::string path = fmt("%s_%zu.bin", prefix.c_str(), count);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + path);
  std::vector<PelageRoot> roots(count + 1);
  const size_t got = std::fread(roots.data(), sizeof(PelageRoot), roots.size(), f);
  std::fclose(f);
  if (got != count) throw std::runtime_error(fmt("%s holds %zu roots, not %zu", path.c_str(), got, count));
  roots.resize(count);
  for (const PelageRoot& r : roots) {
    if (r.face >= triangles || !(r.u >= 0.0f && r.v >= 0.0f && r.u + r.v <= 1.0001f)) {
      throw std::runtime_error(path + " holds a root off the mesh");
    }
  }
  return roots;
}

// The random-equivalents of one count's stamped roots.
struct Equivalents {
  size_t count;
  check::Multiple mean, worst;
};

Equivalents coverage(creature::Device& device, const creature::Mesh& mesh, const Coverage& cov,
                     const std::vector<PelageRoot>& roots, const std::vector<double>& cdf, const Options& opt) {
  std::printf("\n(d) skin coverage\n");
  creature::Stopwatch clock;
  const size_t n = roots.size();
  auto measure = [&](const std::vector<PelageRoot>& rs) {
    std::vector<float> p, nr;
    creature::evaluate(mesh, rs, p, nr);
    const creature::Strands s = creature::grow_strands(p, nr, opt.strands);
    RTCScene scene = rtcNewScene(device.device);
    const unsigned id = creature::attach_mesh(device.device, scene, mesh);
    creature::attach_strands(device.device, scene, s);
    rtcCommitScene(scene);
    device.check("coverage scene");
    const Coverage::Seen seen = cov.skin_visible(scene, id);
    rtcReleaseScene(scene);
    return seen;
  };

  struct Row {
    std::string name;
    double multiple;
    size_t count;
    Coverage::Seen seen;
  };
  std::vector<Row> rows;
  rows.push_back({"pelage stamp (Poisson)", 1.0, n, measure(roots)});
  std::optional<Row> reference;
  if (!opt.reference.empty()) {
    reference = Row{"darts (reference)", 1.0, n, measure(load_reference(opt.reference, n, mesh.triangle_count()))};
  }
  for (double m : kMultiples) {
    const size_t count = size_t(std::llround(m * double(n)));
    rows.push_back(
        {fmt("uniform random, %.2fx", m), m, count, measure(random_roots(cdf, count, 1000 + uint64_t(100 * m)))});
  }
  std::printf("  %-26s %10s %14s %14s %14s\n", "roots", "count", "skin visible", "worst (p99)", "bald patches");
  auto print = [](const Row& r) {
    std::printf("  %-26s %10zu %12.2f %% %12.2f %% %12.2f %%\n", r.name.c_str(), r.count, 100.0 * r.seen.skin,
                100.0 * r.seen.worst, 100.0 * r.seen.patches);
  };
  for (const Row& r : rows) print(r);
  if (reference) print(*reference);
  auto match = [&](const Row& of, double Coverage::Seen::*metric) {
    std::vector<std::pair<double, double>> random;
    for (size_t k = 1; k < rows.size(); ++k) random.emplace_back(rows[k].multiple, rows[k].seen.*metric);
    return check::matching_multiple(of.seen.*metric, random);
  };
  const Equivalents eq{n, match(rows[0], &Coverage::Seen::skin), match(rows[0], &Coverage::Seen::worst)};
  std::printf("  %-26s %10s %14s %14s %14s\n", "random-equivalent", "", eq.mean.text().c_str(),
              eq.worst.text().c_str(), match(rows[0], &Coverage::Seen::patches).text().c_str());
  if (reference) {
    const check::Multiple mean = match(*reference, &Coverage::Seen::skin);
    const check::Multiple worst = match(*reference, &Coverage::Seen::worst);
    std::printf("  %-26s %10s %14s %14s %14s\n", "  of the reference", "", mean.text().c_str(), worst.text().c_str(),
                match(*reference, &Coverage::Seen::patches).text().c_str());
    expect(eq.mean.at_least(mean.value - 0.05),
           fmt("mean skin visible: the stamp's random-equivalent %s within 0.05x of the darts' %s",
               eq.mean.text().c_str(), mean.text().c_str()));
    // the 99th percentile of ~1,000 tiles is its ten worst: stamps of
    // seeds 1-4 of the creature at 100K give 1.26x-1.38x with long strands
    expect(eq.worst.at_least(worst.value - 0.15),
           fmt("worst patches (p99): the stamp's random-equivalent %s within 0.15x of the darts' %s",
               eq.worst.text().c_str(), worst.text().c_str()));
  }
  std::printf("  (%.1f s)\n", clock.seconds());

  const size_t tiles = rows[0].seen.tiles;
  expect(tiles >= 100, fmt("%zu tiles on furred skin, enough for a 99th percentile", tiles));
  expect(rows[0].seen.skin < rows[1].seen.skin,
         fmt("stamped roots show less skin than random roots at equal count (%.2f %% < %.2f %%)",
             100.0 * rows[0].seen.skin, 100.0 * rows[1].seen.skin));
  if (opt.min_mean_multiple) {
    expect(eq.mean.at_least(*opt.min_mean_multiple),
           fmt("mean skin visible: random-equivalent %s >= %.2fx", eq.mean.text().c_str(), *opt.min_mean_multiple));
  }
  if (opt.min_p99_multiple) {
    expect(eq.worst.at_least(*opt.min_p99_multiple),
           fmt("worst patches (p99): random-equivalent %s >= %.2fx", eq.worst.text().c_str(), *opt.min_p99_multiple));
  }
  return eq;
}

// --- (e) spacing ------------------------------------------------------------
void spacing(const creature::Mesh& mesh, const std::vector<PelageRoot>& roots, const std::vector<float>& positions,
             const std::vector<double>& cdf, float radius) {
  std::printf("\n(e) spacing: nearest same-side neighbour of each root\n");
  const float reach = 4.0f * radius;
  const std::vector<PelageRoot> random = random_roots(cdf, roots.size(), 1010);
  std::vector<float> rp, rn;
  creature::evaluate(mesh, random, rp, rn);
  const std::vector<float> stamped_nn = nearest_neighbours(mesh, roots, positions, reach);
  const std::vector<float> random_nn = nearest_neighbours(mesh, random, rp, reach);
  auto stats = [&](const char* name, std::vector<float> d) {
    std::sort(d.begin(), d.end());
    double mean = 0.0;
    for (float x : d) mean += x;
    mean /= double(d.size());
    const size_t below = size_t(std::lower_bound(d.begin(), d.end(), radius) - d.begin());
    std::printf("  %-24s min %.5f (%.3f r)  median %.5f  mean %.5f  closer than r: %6.2f %%\n", name,
                double(d.front()), double(d.front() / radius), double(d[d.size() / 2]), mean,
                100.0 * double(below) / double(d.size()));
    return std::make_pair(double(d.front()), mean);
  };
  std::printf("  disk radius r = %.5f; distances capped at 4 r\n", double(radius));
  const auto st = stats("pelage stamp (Poisson)", stamped_nn);
  const auto rd = stats("uniform random, 1.0x", random_nn);
  std::printf("  mean nearest-neighbour distance, stamped / random: %.2f\n", st.second / rd.second);
  expect(st.first >= 0.999 * double(radius), "no two same-side stamped roots closer than the disk radius");
}

}  // namespace

int main(int argc, char** argv) try {
  const Options opt = parse(argc, argv);
  creature::Stopwatch total;
  const creature::Mesh mesh = creature::load_obj(opt.obj);
  const bool has_map = !opt.density.empty();
  // Without a map, one white texel stands for pelage's constant 1 in the
  // harness's own lookups (random roots, furred skin).
  const creature::GrayImage density = has_map ? creature::load_png_gray(opt.density) : creature::GrayImage{1, 1, {255}};
  std::printf("mesh: %zu vertices, %zu triangles; density %s\n", mesh.vertex_count(), mesh.triangle_count(),
              has_map ? fmt("%dx%d", density.width, density.height).c_str() : "constant 1 (no map)");
  if (mesh.uvs.empty() || mesh.normals.empty()) throw std::runtime_error("the mesh needs vt and vn");

  PelageStampParams params = pelage_stamp_params_defaults();
  params.seed = opt.seed;
  if (has_map) params.density = density.map();
  params.black_scale = 0.5f;
  const std::vector<double> cdf = random_root_cdf(mesh, density, params);

  creature::Device device;
  Coverage cov(mesh, density, opt.resolution);
  {
    RTCScene skin = rtcNewScene(device.device);
    creature::attach_mesh(device.device, skin, mesh);
    rtcCommitScene(skin);
    cov.prepare(skin);
    rtcReleaseScene(skin);
  }
  const creature::StrandParams& sp = opt.strands;
  std::printf("\nskin coverage, (d) at every count:\n");
  std::printf("  %zu orthographic views (", cov.views.size());
  for (size_t v = 0; v < cov.views.size(); ++v) std::printf("%s%s", v ? ", " : "", cov.views[v].name);
  std::printf(") of %dx%d rays (%.4f apart); %zu rays hit furred skin (density texel > 0) when there is no fur.\n",
              cov.resolution, cov.resolution, double(2.0f * cov.half / float(cov.resolution)), cov.furred_rays);
  std::printf("  Strands: straight, length %.3f, radius %.4f%s, %.0f degrees from the normal, combed toward -y.\n",
              double(sp.length), double(sp.root_radius), opt.relative ? " (times the disk radius)" : "",
              double(sp.tilt_root_deg));
  std::printf("  Random roots: area x density-scale^2 weighted, bald triangles excluded (pelage's rule).\n");
  std::printf("  skin visible: share of those rays whose first hit is the skin, not a strand.\n");
  std::printf("  Tiles: %dx%d rays of one view, all on furred skin. worst (p99): the 99th percentile over tiles\n"
              "  of the share of a tile's rays that see skin; bald patches: share of tiles where >= 25 %% do.\n",
              Coverage::tile, Coverage::tile);
  std::printf("  random-equivalent: the multiple of random roots that matches the stamped value (linear between\n"
              "  the multiples measured, never extrapolated: \"< %.2fx\" or \"> %.2fx\" outside them).\n",
              kMultiples[0], std::end(kMultiples)[-1]);

  std::vector<Equivalents> summary;
  for (uint32_t target : opt.roots) {
    std::printf("\n======== %u roots ========\n", target);
    params.target_count = target;
    PelageStampInfo info{};
    creature::Stopwatch clock;
    const std::vector<PelageRoot> roots = creature::stamp(mesh, params, &info);
    const double stamp_s = clock.seconds();
    const size_t n = roots.size();
    std::printf("stamp: %zu roots for a target of %u in %.3f s (query + allocation + stamp: %.2f M roots/s); "
                "radius %.5f, %u passes, %u candidates, %u pruned, %u degenerate triangles\n",
                n, target, stamp_s, double(n) / stamp_s * 1e-6, info.radius, info.passes, info.candidates, info.pruned,
                info.degenerate_triangles);
    expect(std::fabs(double(n) - target) <= 0.03 * target, fmt("count %zu within 3%% of %u", n, target));

    std::vector<float> positions, normals;
    creature::evaluate(mesh, roots, positions, normals);
    on_surface(device, mesh, roots, positions, normals);
    if (has_map) {
      bald_regions(mesh, density, roots, params.bald_below);
    } else {
      std::printf("\n(b) bald regions: none (constant density)\n");
    }
    Options here = opt;
    if (opt.relative) {
      here.strands.length = sp.length * info.radius;
      here.strands.root_radius = here.strands.tip_radius = sp.root_radius * info.radius;
      std::printf("strands: length %.4f, radius %.4f\n", double(here.strands.length),
                  double(here.strands.root_radius));
    }
    curves(device, mesh, creature::grow_strands(positions, normals, here.strands), here.strands);
    summary.push_back(coverage(device, mesh, cov, roots, cdf, here));
    spacing(mesh, roots, positions, cdf, info.radius);
  }

  std::printf("\nrandom-equivalents of the stamped roots (issue 30 asks >= 1.35x mean, >= 1.50x worst patches)\n");
  std::printf("  %10s %14s %14s\n", "roots", "mean", "worst (p99)");
  for (const Equivalents& e : summary) {
    std::printf("  %10zu %14s %14s\n", e.count, e.mean.text().c_str(), e.worst.text().c_str());
  }

  device.check("end");
  std::printf("\nembree_stamp: %s (%d failed checks) in %.1f s\n", check::failures ? "FAILED" : "passed", check::failures,
              total.seconds());
  return check::failures ? EXIT_FAILURE : EXIT_SUCCESS;
} catch (const std::exception& e) {
  std::fprintf(stderr, "embree_stamp: %s\n", e.what());
  return EXIT_FAILURE;
}
