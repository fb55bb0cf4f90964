//! Strand-to-strand interaction at the tips (paper 3.2): at rest each tip
//! is linked to its nearest tips (at most `max_links`, within `radius`),
//! both ways, with the rest distance; each step relaxes the spring targets
//! of the tips toward those distances a few times. Each relaxation reads a
//! snapshot of every target and writes each tip's own (Jacobi), so any
//! split of the tips over threads gives the same bits.

use crate::arena::{Arena, ArenaLayout};
use crate::surface::grid::HashGrid;
use crate::surface::mesh::MAX_COORDINATE;
use crate::Error;
use glam::Vec3;

/// Link parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkParams {
    /// Tips closer than this at rest may be linked (world units, 0: no links).
    pub radius: f32,
    /// Most links a tip makes to its nearest tips (0..=16); a tip may end
    /// with more, from tips that chose it.
    pub max_links: u32,
    /// Relaxations per step (0..=16).
    pub iterations: u32,
    /// Share of its links' mean correction a tip takes per relaxation (0..=1).
    pub stiffness: f32,
}

impl Default for LinkParams {
    fn default() -> Self {
        LinkParams {
            radius: 0.0,
            max_links: 4,
            iterations: 2,
            stiffness: 0.5,
        }
    }
}

/// Most links a tip makes itself.
pub const MAX_LINKS: u32 = 16;

impl LinkParams {
    /// True when every value is finite and in its range.
    pub fn is_valid(&self) -> bool {
        (0.0..=MAX_COORDINATE).contains(&self.radius)
            && self.max_links <= MAX_LINKS
            && self.iterations <= 16
            && (0.0..=1.0).contains(&self.stiffness)
    }

    fn active(&self) -> bool {
        self.radius > 0.0 && self.max_links > 0
    }
}

/// The link network: tip `i`'s links are `to[offsets[i]..offsets[i + 1]]`
/// with rest lengths `rest` alike, ordered by the other tip's index.
pub struct Links<'a> {
    offsets: &'a [u32],
    to: &'a [u32],
    rest: &'a [f32],
}

impl<'a> Links<'a> {
    /// Adds the arena bytes [`Links::new`] needs for `tips` tips.
    pub fn layout(layout: &mut ArenaLayout, tips: usize, params: &LinkParams) {
        let k = if params.active() {
            params.max_links as usize
        } else {
            0
        };
        let most = tips.saturating_mul(k).saturating_mul(2);
        layout.add::<u32>(tips.saturating_add(1));
        layout.add::<u32>(most);
        layout.add::<f32>(most);
        if k > 0 {
            // the search: a grid, and each tip's own choice
            layout.add::<u32>(HashGrid::buckets_for(tips));
            layout.add::<u32>(tips);
            layout.add::<u32>(tips.saturating_mul(k));
            layout.add::<u32>(tips.saturating_add(1));
        }
    }

    /// Links the rest `tips`.
    pub fn new(
        tips: &[[f32; 3]],
        params: &LinkParams,
        arena: &mut Arena<'a>,
    ) -> Result<Self, Error> {
        let n = tips.len();
        let tip = |i: usize| Vec3::from(tips[i]);
        let offsets = arena.alloc::<u32>(n + 1)?;
        offsets.fill(0);
        if !params.active() || n < 2 {
            return Ok(Links {
                offsets,
                to: &[],
                rest: &[],
            });
        }
        let k = params.max_links as usize;
        // each tip's nearest within the radius, by distance then index
        let chosen = {
            let heads = arena.alloc::<u32>(HashGrid::buckets_for(n))?;
            let next = arena.alloc::<u32>(n)?;
            let mut grid = HashGrid::new(heads, next, params.radius);
            for i in 0..n {
                grid.insert(i as u32, tip(i));
            }
            let chosen = arena.alloc::<u32>(n * k)?;
            chosen.fill(u32::MAX);
            for i in 0..n {
                let p = tip(i);
                let mine = &mut chosen[i * k..(i + 1) * k];
                let mut dist = [f32::INFINITY; MAX_LINKS as usize];
                grid.any_within(p, params.radius, |j| {
                    let d = p.distance(tip(j as usize));
                    if j as usize != i && d <= params.radius {
                        // insertion into the sorted few
                        let mut at = k;
                        while at > 0 && (d, j) < (dist[at - 1], mine[at - 1]) {
                            at -= 1;
                        }
                        if at < k {
                            for m in (at + 1..k).rev() {
                                (dist[m], mine[m]) = (dist[m - 1], mine[m - 1]);
                            }
                            (dist[at], mine[at]) = (d, j);
                        }
                    }
                    false
                });
            }
            &*chosen
        };
        let picked = |i: usize| {
            chosen[i * k..(i + 1) * k]
                .iter()
                .take_while(|&&j| j != u32::MAX)
        };
        let chose = |i: usize, j: u32| picked(i).any(|&m| m == j);
        // both ways: i's own choices, and every tip that chose i without i choosing it
        let counts = arena.alloc::<u32>(n + 1)?;
        counts.fill(0);
        for i in 0..n {
            for &j in picked(i) {
                counts[i] += 1;
                if !chose(j as usize, i as u32) {
                    counts[j as usize] += 1;
                }
            }
        }
        offsets[0] = 0;
        for i in 0..n {
            offsets[i + 1] = offsets[i] + counts[i];
        }
        let total = offsets[n] as usize;
        let to = arena.alloc::<u32>(total)?;
        let rest = arena.alloc::<f32>(total)?;
        counts.fill(0);
        let mut add = |a: usize, b: u32| {
            let at = (offsets[a] + counts[a]) as usize;
            to[at] = b;
            counts[a] += 1;
        };
        for i in 0..n {
            for &j in picked(i) {
                add(i, j);
                if !chose(j as usize, i as u32) {
                    add(j as usize, i as u32);
                }
            }
        }
        for i in 0..n {
            let row = offsets[i] as usize..offsets[i + 1] as usize;
            to[row.clone()].sort_unstable();
            for at in row {
                rest[at] = tip(i).distance(tip(to[at] as usize));
            }
        }
        Ok(Links { offsets, to, rest })
    }

    /// Number of links (each counted from both ends).
    pub fn len(&self) -> usize {
        self.to.len()
    }

    /// True without links.
    pub fn is_empty(&self) -> bool {
        self.to.is_empty()
    }

    /// Tip `i`'s target after one relaxation against the `snapshot` of
    /// every target.
    pub fn relaxed(&self, i: usize, snapshot: &[[f32; 3]], stiffness: f32) -> Vec3 {
        let p = Vec3::from(snapshot[i]);
        let row = self.offsets[i] as usize..self.offsets[i + 1] as usize;
        if row.is_empty() {
            return p;
        }
        let mut pull = Vec3::ZERO;
        for at in row.clone() {
            let d = Vec3::from(snapshot[self.to[at] as usize]) - p;
            let len = d.length();
            if len > 0.0 {
                pull += d * (0.5 * (len - self.rest[at]) / len);
            }
        }
        p + pull * (stiffness / row.len() as f32)
    }

    /// Total strain: the sum over links of |distance - rest| at `targets`.
    pub fn strain(&self, targets: &[[f32; 3]]) -> f32 {
        let mut sum = 0.0;
        for i in 0..self.offsets.len().saturating_sub(1) {
            for at in self.offsets[i] as usize..self.offsets[i + 1] as usize {
                let d = Vec3::from(targets[i]).distance(Vec3::from(targets[self.to[at] as usize]));
                sum += (d - self.rest[at]).abs();
            }
        }
        sum
    }
}
