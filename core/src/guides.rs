//! Guide hairs: curves rooted on the mesh.

use crate::{Error, Mesh, Root, Strided};
use glam::Vec3;

/// How control vertices are split between guides.
#[derive(Clone, Copy, Debug)]
pub enum CvLayout<'a> {
    /// Every guide has this many control vertices (the fast path).
    Fixed(usize),
    /// Guide `g` owns points `offsets[g]..offsets[g + 1]`; `guide_count + 1` entries.
    Offsets(&'a [u32]),
}

/// A set of guide curves in world space (rest or posed), each rooted on the
/// mesh at `roots[g]` (face and barycentric; `id` and `rank` are not used).
#[derive(Clone, Copy, Debug)]
pub struct Guides<'a> {
    /// Where each guide grows.
    pub roots: &'a [Root],
    /// All control points, guide after guide.
    pub points: Strided<'a, [f32; 3]>,
    /// Control vertices per guide.
    pub layout: CvLayout<'a>,
}

impl Guides<'_> {
    /// Number of guides.
    #[inline]
    pub fn len(&self) -> usize {
        self.roots.len()
    }

    /// True when there is no guide.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.roots.is_empty()
    }

    /// First point index and point count of guide `g`.
    #[inline]
    pub fn span(&self, g: usize) -> (usize, usize) {
        match self.layout {
            CvLayout::Fixed(n) => (g * n, n),
            CvLayout::Offsets(o) => (o[g] as usize, (o[g + 1] - o[g]) as usize),
        }
    }

    /// Control point `j` of guide `g`.
    #[inline]
    pub fn point(&self, g: usize, j: usize) -> Vec3 {
        let (start, _) = self.span(g);
        Vec3::from(self.points.get(start + j))
    }

    /// The guide's polyline at parameter `t` in [0, 1] (uniform in control
    /// vertex index), so guides of any count resample to a common count.
    #[inline]
    pub fn sample(&self, g: usize, t: f32) -> Vec3 {
        let (start, n) = self.span(g);
        let x = t * (n - 1) as f32;
        let i = (x as usize).min(n - 2);
        let f = x - i as f32;
        let a = Vec3::from(self.points.get(start + i));
        let b = Vec3::from(self.points.get(start + i + 1));
        a + (b - a) * f
    }

    /// Polyline length of guide `g`.
    pub fn length(&self, g: usize) -> f32 {
        let (_, n) = self.span(g);
        (1..n)
            .map(|j| self.point(g, j).distance(self.point(g, j - 1)))
            .sum()
    }

    /// Checks layout, roots against `mesh`, and every point; rejects empty
    /// sets, guides with fewer than two points or zero length.
    pub fn validate(&self, mesh: &Mesh) -> Result<(), Error> {
        if self.roots.is_empty() {
            return Err(Error::InvalidArgument("no guides"));
        }
        let expected = match self.layout {
            CvLayout::Fixed(n) => {
                if n < 2 {
                    return Err(Error::InvalidArgument(
                        "guides need at least 2 control points",
                    ));
                }
                self.roots.len().checked_mul(n)
            }
            CvLayout::Offsets(o) => {
                if o.len() != self.roots.len() + 1 || o[0] != 0 {
                    return Err(Error::InvalidArgument(
                        "guide offsets need guide_count + 1 entries starting at 0",
                    ));
                }
                if o.windows(2).any(|w| w[1] < w[0].saturating_add(2)) {
                    return Err(Error::InvalidArgument(
                        "guide offsets must grow by at least 2 per guide",
                    ));
                }
                Some(o[o.len() - 1] as usize)
            }
        };
        if expected != Some(self.points.len()) {
            return Err(Error::InvalidArgument(
                "guide point count does not match the layout",
            ));
        }
        if let Some(i) = self
            .points
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()))
        {
            return Err(Error::NonFinite {
                what: "guide points",
                index: i,
            });
        }
        let limit = crate::surface::mesh::MAX_COORDINATE;
        if let Some(index) = self
            .points
            .iter()
            .position(|p| p.iter().any(|c| c.abs() > limit))
        {
            return Err(Error::OutOfDomain {
                what: "guide points (within 1e9)",
                index,
            });
        }
        crate::root::check_roots(mesh, self.roots, "guide roots")?;
        for g in 0..self.roots.len() {
            let len = self.length(g);
            if len.is_nan() || len <= 0.0 {
                return Err(Error::InvalidArgument("a guide has zero length"));
            }
        }
        Ok(())
    }
}
