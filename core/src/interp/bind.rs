//! Binding render strands to guides (once per groom, at rest).
//!
//! For each strand: the guides whose roots are near the strand's root, that
//! face the same way (the paper's reverse-normal exclusion), that share its
//! parting region, that lie within a search radius scaled by the local
//! guide spacing (so guides across a gap are not used), and that no other
//! part of the body hides: where their normals are far apart, the path
//! between the roots, lifted off the skin, must not cross the rest mesh
//! (the one test that does not fade in, as a part in between does not
//! either). The paper's
//! randomized neighbour count picks how many to keep; weights are inverse
//! distance, faded so each goes continuously to zero as its guide leaves the
//! set: `w_i = (d_next - d_i) / d_i`, with `d_next` the distance of the first
//! guide not kept (or the search radius). The normal and wrap tests fade in
//! too: a guide near either cutoff counts as farther away, so on a curved
//! skin a guide leaves the set by sliding past `d_next`, never by a jump.

use crate::arena::{Arena, ArenaLayout};
use crate::guides::Guides;
use crate::rng::{self, Purpose};
use crate::surface::body::Body;
use crate::surface::grid::HashGrid;
use crate::{Error, Mesh, RegionMap, Root};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Most guides a strand can use.
pub const MAX_NEIGHBOURS: usize = 8;
/// Marks a strand without eligible guides in [`StrandBinding::clump`].
pub const NO_GUIDE: u32 = u32::MAX;
/// How far the weights of a bound strand may sum from 1. Binding divides
/// each weight by their float32 sum, which leaves them within a few 1e-7
/// of 1 (at most 8 roundings); 1e-4 also takes weights a host rounded to
/// 5 decimals, and is small enough that no strand is measurably longer or
/// shorter than its guides make it.
pub const WEIGHT_SUM_TOLERANCE: f32 = 1e-4;
/// The local guide spacing at a strand is its distance to this many-th
/// nearest eligible guide.
const SPACING_RANK: usize = 3;
/// Local spacing never exceeds this multiple of the mean spacing (bounds the search).
const MAX_SPACING_RATIO: f32 = 3.0;
/// A guide is hidden from a strand when the body lies across the path
/// between their roots, each end lifted off the skin along its normal by
/// this fraction of the roots' distance: the guide grows on another part
/// (a finger's pad seen through the next finger).
const LIFT: f32 = 0.25;
/// Only roots whose normals are further apart than this (a dot product;
/// 37 degrees) can be hidden from each other: closer normals lie on one
/// sheet of skin, and the path test costs about half a microsecond.
const HIDDEN_DOT: f32 = 0.8;

/// Binding parameters.
#[derive(Clone, Copy, Debug)]
pub struct BindParams<'a> {
    /// Fewest guides a strand uses when that many qualify (>= 1); a strand
    /// with fewer eligible guides uses those it has.
    pub min_neighbours: u32,
    /// Most guides a strand uses (<= [`MAX_NEIGHBOURS`]); equal to the
    /// minimum to turn off the paper's per-strand randomization.
    pub max_neighbours: u32,
    /// Seed of the per-strand neighbour count.
    pub seed: u64,
    /// A guide is eligible only if its root normal dotted with the strand's
    /// exceeds this. 0 is the paper's rule (exclude guides facing away); the
    /// default 0.25 also keeps strands on the rim of a thin part from taking
    /// guides that are nearly perpendicular, i.e. from the other face.
    /// Within 0.25 above the cutoff a guide's distance is stretched (its
    /// weight fades to zero at the cutoff).
    pub min_normal_dot: f32,
    /// Search radius in units of the local guide spacing: the distance from
    /// the strand to its third nearest eligible guide (at most 3 mean
    /// spacings). It moves continuously with the strand's root, so it never
    /// cuts a guide off with a jump.
    pub search_factor: f32,
    /// A guide is also excluded when either root lies below the other's
    /// tangent plane by more than this times their distance: the surface
    /// between them wraps around a rim (an ear's edge, a fingertip), so the
    /// guide grows on the far side even though its normal is not reversed.
    /// Above half this slope a guide's distance is stretched (its weight
    /// fades to zero at the cutoff).
    pub max_wrap_slope: f32,
    /// Optional parting regions (per vertex or an id texture); a strand
    /// only uses guides of its own region.
    pub regions: Option<RegionMap<'a>>,
}

impl Default for BindParams<'_> {
    fn default() -> Self {
        BindParams {
            min_neighbours: 3,
            max_neighbours: 6,
            seed: 0,
            min_normal_dot: 0.25,
            search_factor: 2.5,
            max_wrap_slope: 0.3,
            regions: None,
        }
    }
}

/// Which guides drive one strand, and how much.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct StrandBinding {
    /// Guide indices; the first `count` are used.
    pub guides: [u32; MAX_NEIGHBOURS],
    /// Weights matching `guides`, each in 0..=1; the first `count` sum to
    /// 1 within [`WEIGHT_SUM_TOLERANCE`] (an orphan has none).
    pub weights: [f32; MAX_NEIGHBOURS],
    /// Number of guides used; 0 for an orphan (no eligible guide).
    pub count: u32,
    /// Nearest eligible guide: the strand's clump centre ([`NO_GUIDE`] for orphans).
    pub clump: u32,
}

/// What binding found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BindReport {
    /// Strands with no eligible guide. They expand as straight strands along
    /// their normal, `mean_guide_length` long (see `ExpandParams::orphan_length`).
    pub orphans: u32,
    /// Mean rest length of the guides.
    pub mean_guide_length: f32,
    /// Mean guide spacing, sqrt(mesh area / guide count).
    pub mean_spacing: f32,
    /// Guide roots the searches looked at, over all strands. Per strand it
    /// is the search's cost, and it stays flat as guides are added (the
    /// search walks the grid cells around the strand, not every guide).
    pub examined: u64,
}

impl BindReport {
    /// Adds the counts (orphans, examined guides) of another range of
    /// strands bound with the same index.
    pub fn merge(&mut self, other: BindReport) {
        self.orphans += other.orphans;
        self.examined += other.examined;
    }
}

/// Guide roots in a spatial grid, with their normals and regions.
pub struct GuideIndex<'a> {
    position: &'a [[f32; 3]],
    normal: &'a [[f32; 3]],
    region: &'a [u32],
    grid: HashGrid<'a>,
    /// The rest mesh as a solid, for the paths from strands to guides.
    body: Body<'a>,
    /// The first search radius: the largest local spacing.
    reach: f32,
    report: BindReport,
}

fn check(params: &BindParams, mesh: &Mesh) -> Result<(), Error> {
    if params.min_neighbours == 0 || params.max_neighbours as usize > MAX_NEIGHBOURS {
        return Err(Error::InvalidArgument("neighbour counts must be in 1..=8"));
    }
    if params.min_neighbours > params.max_neighbours {
        return Err(Error::InvalidArgument(
            "min_neighbours exceeds max_neighbours",
        ));
    }
    for (what, value) in [
        ("min_normal_dot", params.min_normal_dot),
        ("search_factor", params.search_factor),
        ("max_wrap_slope", params.max_wrap_slope),
    ] {
        if !value.is_finite() {
            return Err(Error::NonFinite { what, index: 0 });
        }
    }
    if params.search_factor <= 0.0 {
        return Err(Error::InvalidArgument("search_factor must be positive"));
    }
    if params.max_wrap_slope <= 0.0 {
        return Err(Error::InvalidArgument("max_wrap_slope must be positive"));
    }
    match params.regions {
        Some(map) => map.validate(mesh),
        None => Ok(()),
    }
}

fn region_of(mesh: &Mesh, regions: Option<RegionMap>, r: &Root) -> u32 {
    regions.map_or(0, |map| map.region(mesh, r))
}

/// Width of the fade below [`BindParams::min_normal_dot`]'s cutoff, in
/// units of the normals' dot product.
const NORMAL_FADE: f32 = 0.25;
/// Width of the fade below [`BindParams::max_wrap_slope`]'s cutoff, as a
/// fraction of it.
const WRAP_FADE: f32 = 0.5;

/// How open the eligibility gates are for a guide at offset `d` (`d2` its
/// squared length) with root normal `gn`, from a strand with normal `n`: 1
/// well inside both, falling linearly to 0 at the normal and wrap cutoffs
/// and 0 beyond. A guide's distance is divided by it, so a guide nearing a
/// cutoff slides continuously out of the neighbour set (its weight reaches
/// zero where it leaves) instead of dropping out with a jump.
fn gate(d: Vec3, d2: f32, n: Vec3, gn: Vec3, params: &BindParams) -> f32 {
    let facing = (gn.dot(n) - params.min_normal_dot) / NORMAL_FADE;
    // how far each root lies below the other's tangent plane, per unit of
    // their distance; a strand on a guide's root is level with it
    let dist = libm::sqrtf(d2);
    let below = if dist > 0.0 {
        (-d.dot(n)).max(d.dot(gn)) / dist
    } else {
        0.0
    };
    let level = (1.0 - below / params.max_wrap_slope) / WRAP_FADE;
    facing.clamp(0.0, 1.0) * level.clamp(0.0, 1.0)
}

/// Up to N nearest (distance^2, guide) pairs, sorted.
struct Nearest<const N: usize> {
    items: [(f32, u32); N],
    len: usize,
}

impl<const N: usize> Nearest<N> {
    fn new() -> Self {
        Nearest {
            items: [(f32::INFINITY, 0); N],
            len: 0,
        }
    }

    /// Whether [`push`](Self::push) would keep `(d2, g)`.
    fn takes(&self, d2: f32, g: u32) -> bool {
        self.len < N || (d2, g) < self.items[N - 1]
    }

    /// Inserts keeping order; ties break on guide index so results never
    /// depend on grid traversal order. The grid may report a guide twice
    /// (two cells sharing a bucket); the second report is ignored.
    fn push(&mut self, d2: f32, g: u32) {
        if self.len == N && (d2, g) >= self.items[N - 1]
            || self.items[..self.len].contains(&(d2, g))
        {
            return;
        }
        let mut i = self.len.min(N - 1);
        while i > 0 && (d2, g) < self.items[i - 1] {
            self.items[i] = self.items[i - 1];
            i -= 1;
        }
        self.items[i] = (d2, g);
        self.len = (self.len + 1).min(N);
    }
}

impl<'a> GuideIndex<'a> {
    /// Adds the arena bytes [`GuideIndex::new`] needs for `guides` guides
    /// on `mesh` (validates the mesh).
    pub fn layout(layout: &mut ArenaLayout, mesh: &Mesh, guides: usize) -> Result<(), Error> {
        layout.add::<u8>(Body::required_bytes(mesh)?);
        layout
            .add::<[f32; 3]>(guides)
            .add::<[f32; 3]>(guides)
            .add::<u32>(guides)
            .add::<u32>(HashGrid::buckets_for(guides))
            .add::<u32>(guides);
        Ok(())
    }

    /// Validates the rest mesh, rest guides and parameters and indexes the guides.
    pub fn new(
        mesh: &Mesh,
        guides: &Guides,
        params: &BindParams,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        check(params, mesh)?;
        let area = mesh.validate()?.area;
        guides.validate(mesh)?;
        let body = Body::new(mesh, arena)?;
        let n = guides.len();
        let position = arena.alloc::<[f32; 3]>(n)?;
        let normal = arena.alloc::<[f32; 3]>(n)?;
        let region = arena.alloc::<u32>(n)?;
        let heads = arena.alloc::<u32>(HashGrid::buckets_for(n))?;
        let next = arena.alloc::<u32>(n)?;
        let mean_spacing = libm::sqrt(area / n as f64) as f32;
        let cell = params.search_factor * mean_spacing;
        let mut grid = HashGrid::new(heads, next, cell);
        let mut total_length = 0.0f64;
        for (g, r) in guides.roots.iter().enumerate() {
            let p = mesh.point(r.face as usize, r.u, r.v);
            position[g] = p.into();
            normal[g] = mesh.normal(r.face as usize, r.u, r.v).into();
            region[g] = region_of(mesh, params.regions, r);
            total_length += guides.length(g) as f64;
            grid.insert(g as u32, p);
        }
        Ok(GuideIndex {
            position,
            normal,
            region,
            grid,
            body,
            reach: MAX_SPACING_RATIO * mean_spacing,
            report: BindReport {
                orphans: 0,
                mean_guide_length: (total_length / n as f64) as f32,
                mean_spacing,
                examined: 0,
            },
        })
    }

    /// Mean length and spacing of the guides (orphans and examined guides
    /// are counted by `bind`).
    pub fn report(&self) -> BindReport {
        self.report
    }

    /// Binds `strands` into `out` (same length); returns the report with
    /// their orphans and examined guides counted. Pure per strand: disjoint
    /// ranges can run on different threads.
    pub fn bind(
        &self,
        mesh: &Mesh,
        strands: &[Root],
        params: &BindParams,
        out: &mut [StrandBinding],
    ) -> Result<BindReport, Error> {
        check(params, mesh)?;
        if out.len() < strands.len() {
            return Err(Error::OutputTooSmall {
                needed: strands.len(),
                available: out.len(),
            });
        }
        crate::root::check_roots(mesh, strands, "strand roots")?;
        let mut report = self.report;
        for (r, b) in strands.iter().zip(out.iter_mut()) {
            let examined;
            (*b, examined) = self.bind_one(mesh, r, params);
            report.orphans += (b.count == 0) as u32;
            report.examined += examined as u64;
        }
        Ok(report)
    }

    /// Whether the body hides a guide at offset `d` (`d2` its squared
    /// length) with root normal `gn` from a strand at `p` with normal `n`
    /// (see [`LIFT`]); the path is only walked where the normals are far
    /// enough apart for a part to come between.
    fn hidden(&self, p: Vec3, n: Vec3, d: Vec3, d2: f32, gn: Vec3) -> bool {
        if gn.dot(n) >= HIDDEN_DOT {
            return false;
        }
        let lift = LIFT * libm::sqrtf(d2);
        self.body.blocks(p + n * lift, p + d + gn * lift)
    }

    /// The binding of one strand, and how many guide roots its search
    /// looked at.
    fn bind_one(&self, mesh: &Mesh, r: &Root, params: &BindParams) -> (StrandBinding, u32) {
        let face = r.face as usize;
        let p = mesh.point(face, r.u, r.v);
        let n = mesh.normal(face, r.u, r.v);
        let region = region_of(mesh, params.regions, r);
        let mut examined = 0;
        let mut gather = |radius: f32| {
            let mut near = Nearest::<{ MAX_NEIGHBOURS + 1 }>::new();
            self.grid.any_within(p, radius, |g| {
                examined += 1;
                let gi = g as usize;
                let d = Vec3::from(self.position[gi]) - p;
                let d2 = d.length_squared();
                // the grid visits a cube; the search is a ball
                if d2 >= radius * radius || self.region[gi] != region {
                    return false;
                }
                let gn = Vec3::from(self.normal[gi]);
                let open = gate(d, d2, n, gn, params);
                if open > 0.0 {
                    let gated = d2 / (open * open);
                    if gated < radius * radius
                        && near.takes(gated, g)
                        && !self.hidden(p, n, d, d2, gn)
                    {
                        near.push(gated, g);
                    }
                }
                false
            });
            near
        };
        let mut near = gather(self.reach);
        let orphan = StrandBinding {
            clump: crate::interp::bind::NO_GUIDE,
            ..StrandBinding::default()
        };
        if near.len == 0 {
            return (orphan, examined);
        }
        // a guide missing from the gather lies beyond `reach`, the cap
        let spacing = match near.len {
            len if len >= SPACING_RANK => libm::sqrtf(near.items[SPACING_RANK - 1].0),
            _ => self.reach,
        };
        let radius = params.search_factor * spacing.min(self.reach);
        if radius > self.reach {
            near = gather(radius);
        }
        let within = near.items[..near.len]
            .iter()
            .take_while(|(d2, _)| *d2 < radius * radius)
            .count();
        if within == 0 {
            return (orphan, examined);
        }
        let span = params.max_neighbours - params.min_neighbours + 1;
        let k = params.min_neighbours
            + (rng::hash(params.seed, r.id as u64, Purpose::NeighbourCount, 0) % span as u64)
                as u32;
        let k = (k as usize).min(within);
        let d_next = if within > k {
            libm::sqrtf(near.items[k].0)
        } else {
            radius
        };
        let floor = 1e-6 * self.report.mean_spacing;
        let mut b = StrandBinding {
            count: k as u32,
            clump: near.items[0].1,
            ..StrandBinding::default()
        };
        let mut sum = 0.0;
        for i in 0..k {
            let d = libm::sqrtf(near.items[i].0);
            let w = (d_next - d).max(0.0) / d.max(floor);
            b.guides[i] = near.items[i].1;
            b.weights[i] = w;
            sum += w;
        }
        if sum > 0.0 {
            for w in &mut b.weights[..k] {
                *w /= sum;
            }
        } else {
            b.weights[0] = 1.0;
        }
        (b, examined)
    }
}

/// Arena bytes [`bind`] needs for `guides` guides on `mesh` (validates
/// the mesh).
pub fn required_bytes(mesh: &Mesh, guides: usize) -> Result<usize, Error> {
    let mut layout = ArenaLayout::new();
    GuideIndex::layout(&mut layout, mesh, guides)?;
    Ok(layout.bytes())
}

/// Binds every strand (rest mesh, rest guides) into `out`.
pub fn bind(
    mesh: &Mesh,
    guides: &Guides,
    strands: &[Root],
    params: &BindParams,
    arena: &mut Arena,
    out: &mut [StrandBinding],
) -> Result<BindReport, Error> {
    if out.len() < strands.len() {
        return Err(Error::OutputTooSmall {
            needed: strands.len(),
            available: out.len(),
        });
    }
    let index = GuideIndex::new(mesh, guides, params, arena)?;
    index.bind(mesh, strands, params, out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::guides::CvLayout;
    use crate::testmesh::{graded_plane, roots, straight_guides, TestMesh};
    use crate::Strided;

    /// Two parallel squares 0.01 apart facing away from each other: the two
    /// sides of an ear.
    fn slab() -> TestMesh {
        let top = graded_plane(10, 1.0);
        let mut p = top.p.clone();
        let n = p.len() as u32;
        p.extend(top.p.iter().map(|q| [q[0], q[1], -0.01]));
        let mut t = top.t.clone();
        t.extend(top.t.iter().map(|f| [f[0] + n, f[2] + n, f[1] + n]));
        let mut uv = top.uv.clone();
        uv.extend(top.uv.iter());
        TestMesh {
            p,
            t,
            uv,
            n: vec![],
        }
    }

    fn run(
        m: &TestMesh,
        g: &[Root],
        pts: &[[f32; 3]],
        strands: &[Root],
        params: &BindParams,
    ) -> Result<(Vec<StrandBinding>, BindReport), Error> {
        let guides = Guides {
            roots: g,
            points: Strided::from_slice(pts),
            layout: CvLayout::Fixed(4),
        };
        let mut buf = vec![0u8; required_bytes(&m.mesh(), g.len()).unwrap_or(0)];
        let mut out = vec![StrandBinding::default(); strands.len()];
        let report = bind(
            &m.mesh(),
            &guides,
            strands,
            params,
            &mut Arena::new(&mut buf),
            &mut out,
        )?;
        Ok((out, report))
    }

    #[test]
    fn never_takes_a_guide_from_the_other_side_of_a_thin_part() {
        let m = slab();
        let mesh = m.mesh();
        let g = roots(mesh, 300, 1);
        let pts = straight_guides(&mesh, &g, 4, 0.05);
        let strands = roots(mesh, 5000, 2);
        let (b, report) = run(&m, &g, &pts, &strands, &BindParams::default()).unwrap();
        assert_eq!(report.orphans, 0);
        let top = |f: u32| (f as usize) < mesh.triangle_count() / 2;
        for (s, bind) in strands.iter().zip(&b) {
            assert!(bind.count > 0);
            for &gi in &bind.guides[..bind.count as usize] {
                assert_eq!(
                    top(s.face),
                    top(g[gi as usize].face),
                    "strand crossed the slab"
                );
            }
            let w: f32 = bind.weights[..bind.count as usize].iter().sum();
            assert!((w - 1.0).abs() < 1e-5);
        }
    }

    /// A floor (normal +z) running into a ramp (normal (-1, 0, 1) / sqrt 2)
    /// at x = 0.6, and a small closed tetrahedron centred on `block`.
    fn floor_ramp_and_block(block: [f32; 3]) -> TestMesh {
        let mut p = vec![
            [0.0, 0.0, 0.0],
            [0.6, 0.0, 0.0],
            [0.6, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.8, 0.0, 0.2],
            [0.8, 1.0, 0.2],
        ];
        let s = 0.012;
        for d in [
            [1.0, 1.0, 1.0],
            [1.0, -1.0, -1.0],
            [-1.0, 1.0, -1.0],
            [-1.0, -1.0, 1.0],
        ] {
            p.push([0, 1, 2].map(|k| block[k] + s * d[k]));
        }
        let t = vec![
            [0, 1, 2],
            [0, 2, 3],
            [1, 4, 5],
            [1, 5, 2],
            [6, 7, 8],
            [6, 9, 7],
            [6, 8, 9],
            [7, 9, 8],
        ];
        TestMesh {
            uv: vec![[0.0; 2]; p.len()],
            p,
            t,
            n: vec![],
        }
    }

    #[test]
    fn a_guide_behind_another_part_of_the_body_is_hidden() {
        let root = |face, u, v| Root {
            face,
            u,
            v,
            ..Root::default()
        };
        // the strand at (0.5, 0.5) on the floor, three guides 0.2 away on
        // it and the nearest, 0.16 away, on the ramp at (0.65, 0.5, 0.05)
        let strands = [root(0, 1.0 / 3.0, 0.5)];
        let g = [
            root(1, 0.5, 0.0),
            root(0, 0.8 / 1.5, 0.3),
            root(0, 0.2 / 1.5, 0.7),
            root(3, 0.25, 0.25),
        ];
        let uses_ramp = |block| {
            let m = floor_ramp_and_block(block);
            let pts = straight_guides(&m.mesh(), &g, 4, 0.05);
            let (b, _) = run(&m, &g, &pts, &strands, &BindParams::default()).unwrap();
            assert!(b[0].count >= 3);
            b[0].guides[..b[0].count as usize].contains(&3)
        };
        // far away, the block hides nothing; on the path between the roots,
        // lifted off the skin, it hides the ramp's guide
        assert!(uses_ramp([5.0, 0.5, 0.06]));
        assert!(!uses_ramp([0.561, 0.5, 0.059]));
    }

    #[test]
    fn neighbour_counts_spread_over_the_range_keyed_by_strand_id() {
        let m = graded_plane(12, 1.0);
        let mesh = m.mesh();
        let g = roots(mesh, 400, 1);
        let pts = straight_guides(&mesh, &g, 4, 0.05);
        let strands = roots(mesh, 3000, 2);
        let params = BindParams {
            min_neighbours: 2,
            max_neighbours: 6,
            ..BindParams::default()
        };
        let (b, _) = run(&m, &g, &pts, &strands, &params).unwrap();
        let mut histogram = [0usize; MAX_NEIGHBOURS + 1];
        for bind in &b {
            histogram[bind.count as usize] += 1;
        }
        // a count below the minimum only where fewer guides are in reach
        // (the plane's border); every count of the range is well used
        assert_eq!(histogram[7..].iter().sum::<usize>(), 0, "{histogram:?}");
        assert!(
            histogram[..2].iter().sum::<usize>() < b.len() / 20,
            "{histogram:?}"
        );
        for count in 2..=6 {
            assert!(histogram[count] > b.len() / 10, "{count}: {histogram:?}");
        }
        // keyed by the strand's id, not by its position in the call
        let reversed: Vec<Root> = strands.iter().rev().copied().collect();
        let (rb, _) = run(&m, &g, &pts, &reversed, &params).unwrap();
        assert!(rb.iter().rev().eq(b.iter()));
        let renamed: Vec<Root> = strands
            .iter()
            .map(|r| Root { id: r.id + 7, ..*r })
            .collect();
        let (nb, _) = run(&m, &g, &pts, &renamed, &params).unwrap();
        let changed = b
            .iter()
            .zip(&nb)
            .filter(|(a, n)| a.count != n.count)
            .count();
        assert!(
            changed > b.len() / 2,
            "{changed} of {} counts changed",
            b.len()
        );
    }

    #[test]
    fn partings_and_orphans() {
        let m = graded_plane(12, 1.0);
        let mesh = m.mesh();
        // region 1 on the right half, 0 on the left; guides only on the left
        let regions: Vec<u32> = m.p.iter().map(|p| (p[0] > 0.5) as u32).collect();
        let all = roots(mesh, 400, 1);
        let g: Vec<Root> = all
            .into_iter()
            .filter(|r| mesh.point(r.face as usize, r.u, r.v).x < 0.4)
            .collect();
        let pts = straight_guides(&mesh, &g, 4, 0.05);
        let strands = roots(mesh, 3000, 2);
        let params = BindParams {
            regions: Some(RegionMap::PerVertex(Strided::from_slice(&regions))),
            ..BindParams::default()
        };
        let (b, report) = run(&m, &g, &pts, &strands, &params).unwrap();
        let right = strands
            .iter()
            .filter(|r| region_of(&mesh, params.regions, r) == 1)
            .count();
        // every right-side strand is an orphan (checked below), and a few
        // left-side ones near the border are beyond the search radius
        assert!(report.orphans as usize >= right);
        for (s, bind) in strands.iter().zip(&b) {
            if region_of(&mesh, params.regions, s) == 1 {
                assert_eq!((bind.count, bind.clump), (0, NO_GUIDE));
            }
        }
        // the same parting painted as an id texture (uv = xy on this plane)
        let texels = [0u8, 1];
        let painted = BindParams {
            regions: Some(RegionMap::Texture(crate::surface::map::Texture {
                texels: crate::surface::map::Texels::U8(&texels),
                width: 2,
                height: 1,
                row_stride: 2,
            })),
            ..BindParams::default()
        };
        let (b, _) = run(&m, &g, &pts, &strands, &painted).unwrap();
        for (s, bind) in strands.iter().zip(&b) {
            if mesh.point(s.face as usize, s.u, s.v).x > 0.5 {
                assert_eq!((bind.count, bind.clump), (0, NO_GUIDE));
            }
        }
        // without partings, the distance bound still keeps far strands orphaned
        let (_, report) = run(&m, &g, &pts, &strands, &BindParams::default()).unwrap();
        assert!(report.orphans > 0 && (report.orphans as usize) < right);
    }

    #[test]
    fn bad_input_is_reported() {
        let m = graded_plane(4, 1.0);
        let mesh = m.mesh();
        let g = roots(mesh, 20, 1);
        let pts = straight_guides(&mesh, &g, 4, 0.05);
        let s = roots(mesh, 50, 2);
        let ok = BindParams::default();
        assert!(matches!(
            run(&m, &[], &[], &s, &ok),
            Err(Error::InvalidArgument(_))
        ));
        let mut nan = pts.clone();
        nan[5][0] = f32::NAN;
        assert!(matches!(
            run(&m, &g, &nan, &s, &ok),
            Err(Error::NonFinite { index: 5, .. })
        ));
        let mut flat = pts.clone();
        let first = flat[4];
        flat[4..8].fill(first);
        assert!(matches!(
            run(&m, &g, &flat, &s, &ok),
            Err(Error::InvalidArgument(_))
        ));
        let mut far = g.clone();
        far[3].face = 10_000;
        assert!(matches!(
            run(&m, &far, &pts, &s, &ok),
            Err(Error::OutOfRange { index: 3, .. })
        ));
        let k0 = BindParams {
            min_neighbours: 0,
            ..ok
        };
        assert!(matches!(
            run(&m, &g, &pts, &s, &k0),
            Err(Error::InvalidArgument(_))
        ));
        let swapped = BindParams {
            min_neighbours: 5,
            max_neighbours: 3,
            ..ok
        };
        assert!(matches!(
            run(&m, &g, &pts, &s, &swapped),
            Err(Error::InvalidArgument(_))
        ));
        let mut bad_strand = s.clone();
        bad_strand[0].face = u32::MAX;
        assert!(matches!(
            run(&m, &g, &pts, &bad_strand, &ok),
            Err(Error::OutOfRange { .. })
        ));
    }

    #[test]
    fn the_search_looks_at_a_bounded_number_of_guides() {
        // 64x more guides: a search over all guides would look at 64x as
        // many per strand; the grid looks at about the same number
        let m = graded_plane(16, 1.0);
        let strands = roots(m.mesh(), 2000, 8);
        let per_strand = |guides: u32| {
            let g = roots(m.mesh(), guides, 3);
            let pts = straight_guides(&m.mesh(), &g, 4, 0.1);
            let (_, report) = run(&m, &g, &pts, &strands, &BindParams::default()).unwrap();
            assert_eq!(report.orphans, 0);
            report.examined as f32 / strands.len() as f32
        };
        let (few, many) = (per_strand(250), per_strand(16_000));
        assert!(few > 8.0, "{few} guides looked at per strand");
        assert!(
            many < 2.0 * few,
            "{few} per strand with 250 guides, {many} with 16000"
        );
    }
}
