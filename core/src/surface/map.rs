//! Grayscale maps (density, groom parameters) sampled at mesh points.

use crate::{Error, Mesh, Strided};

/// Storage of a texture's texels.
#[derive(Clone, Copy, Debug)]
pub enum Texels<'a> {
    /// 8-bit values, 0..=255 mapped to 0..=1 (what a grayscale PNG holds).
    U8(&'a [u8]),
    /// 32-bit float values, used as they are (native endianness).
    F32(&'a [u8]),
}

/// A grayscale texture over UV space, bilinearly filtered.
///
/// Texel (x, y) is centred at uv = ((x + 0.5) / width, (y + 0.5) / height);
/// row 0 is at v = 0. Lookups outside [0, 1] clamp to the edge texels.
#[derive(Clone, Copy, Debug)]
pub struct Texture<'a> {
    /// Texel storage.
    pub texels: Texels<'a>,
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Bytes from one row to the next.
    pub row_stride: usize,
}

/// A scalar value over the mesh surface.
#[derive(Clone, Copy, Debug)]
pub enum ScalarMap<'a> {
    /// The same value everywhere.
    Constant(f32),
    /// A texture sampled at the mesh UVs (the mesh must have UVs).
    Texture(Texture<'a>),
    /// One value per mesh vertex, interpolated barycentrically.
    PerVertex(Strided<'a, f32>),
}

impl Texture<'_> {
    fn texel_size(&self) -> usize {
        match self.texels {
            Texels::U8(_) => 1,
            Texels::F32(_) => 4,
        }
    }

    #[inline]
    fn texel(&self, x: usize, y: usize) -> f32 {
        let at = y * self.row_stride + x * self.texel_size();
        match self.texels {
            Texels::U8(b) => b[at] as f32 * (1.0 / 255.0),
            Texels::F32(b) => bytemuck::pod_read_unaligned::<f32>(&b[at..at + 4]),
        }
    }

    /// The raw byte of the texel `uv` falls in, unfiltered (for id maps);
    /// 0 for float texels.
    pub fn nearest_byte(&self, u: f32, v: f32) -> u8 {
        let x = (u * self.width as f32).clamp(0.0, (self.width - 1) as f32) as usize;
        let y = (v * self.height as f32).clamp(0.0, (self.height - 1) as f32) as usize;
        match self.texels {
            Texels::U8(b) => b[y * self.row_stride + x],
            Texels::F32(_) => 0,
        }
    }

    /// Bilinear lookup at `uv`.
    pub fn sample(&self, u: f32, v: f32) -> f32 {
        let fx = (u * self.width as f32 - 0.5).clamp(0.0, (self.width - 1) as f32);
        let fy = (v * self.height as f32 - 0.5).clamp(0.0, (self.height - 1) as f32);
        let (x0, y0) = (fx as usize, fy as usize);
        let (x1, y1) = ((x0 + 1).min(self.width - 1), (y0 + 1).min(self.height - 1));
        let (tx, ty) = (fx - x0 as f32, fy - y0 as f32);
        let top = self.texel(x0, y0) * (1.0 - tx) + self.texel(x1, y0) * tx;
        let bottom = self.texel(x0, y1) * (1.0 - tx) + self.texel(x1, y1) * tx;
        top * (1.0 - ty) + bottom * ty
    }
}

impl ScalarMap<'_> {
    /// Checks sizes and values against `mesh`; every sample is then in bounds.
    pub fn validate(&self, mesh: &Mesh, what: &'static str) -> Result<(), Error> {
        match *self {
            ScalarMap::Constant(c) if !c.is_finite() => Err(Error::NonFinite { what, index: 0 }),
            ScalarMap::Constant(_) => Ok(()),
            ScalarMap::PerVertex(values) => {
                if values.len() != mesh.positions.len() {
                    return Err(Error::InvalidArgument(
                        "per-vertex map size differs from vertex count",
                    ));
                }
                match values.iter().position(|x| !x.is_finite()) {
                    Some(index) => Err(Error::NonFinite { what, index }),
                    None => Ok(()),
                }
            }
            ScalarMap::Texture(t) => {
                if t.width == 0 || t.height == 0 {
                    return Err(Error::InvalidArgument("texture map has zero size"));
                }
                if mesh.uvs.is_none() {
                    return Err(Error::InvalidArgument("texture map needs mesh UVs"));
                }
                let row = t
                    .width
                    .checked_mul(t.texel_size())
                    .ok_or(Error::BadStride { what })?;
                let bytes = match t.texels {
                    Texels::U8(b) | Texels::F32(b) => b,
                };
                let need = t
                    .row_stride
                    .checked_mul(t.height - 1)
                    .and_then(|b| b.checked_add(row))
                    .ok_or(Error::BadStride { what })?;
                if t.row_stride < row || need > bytes.len() {
                    return Err(Error::BadStride { what });
                }
                if let Texels::F32(_) = t.texels {
                    for y in 0..t.height {
                        for x in 0..t.width {
                            if !t.texel(x, y).is_finite() {
                                return Err(Error::NonFinite {
                                    what,
                                    index: y * t.width + x,
                                });
                            }
                        }
                    }
                }
                Ok(())
            }
        }
    }

    /// The map's value at barycentric (u, v) on `face`. Call
    /// [`validate`](Self::validate) first.
    #[inline]
    pub fn sample(&self, mesh: &Mesh, face: usize, u: f32, v: f32) -> f32 {
        match *self {
            ScalarMap::Constant(c) => c,
            ScalarMap::PerVertex(values) => {
                let [i, j, k] = mesh.triangles.get(face);
                values.get(i as usize) * (1.0 - u - v)
                    + values.get(j as usize) * u
                    + values.get(k as usize) * v
            }
            ScalarMap::Texture(t) => match mesh.uv(face, u, v) {
                Some(uv) => t.sample(uv.x, uv.y),
                None => 1.0,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_texture_lookup() {
        let texels = [0u8, 255, 255, 255];
        let t = Texture {
            texels: Texels::U8(&texels),
            width: 2,
            height: 2,
            row_stride: 2,
        };
        assert_eq!(t.sample(0.25, 0.25), 0.0);
        assert_eq!(t.sample(0.75, 0.75), 1.0);
        assert!((t.sample(0.5, 0.25) - 0.5).abs() < 1e-6);
        assert_eq!(t.sample(-3.0, -3.0), 0.0);
    }
}
