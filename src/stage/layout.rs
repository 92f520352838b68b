//! The screen layout a plan fixes before anything runs: the sample grid, the pixel region
//! the primitives touch, the sample region that region needs, and the tile map (which tiles
//! the primitives are binned to). Stages read it; the cycle model takes its tokens from it.

use super::StageId;
use serde::Serialize;

/// The sample grid: `n x n` samples per pixel on a coordinate grid of `2^sub_bits` units per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Grid {
    /// Samples per pixel along an axis.
    pub n: u32,
    /// Coordinate units per pixel are `2^sub_bits`.
    pub sub_bits: u32,
    /// Half the sample spacing in coordinate units: sample `c` is at `(2c + 1) * h`.
    pub h: i64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Grid {
    /// Builds the grid; `sub_bits >= log2(n) + 1` is validated by the hardware config.
    pub fn new(n: u32, sub_bits: u32, width: u32, height: u32) -> Self {
        let h = (1i64 << sub_bits) / (2 * n as i64);
        Self {
            n,
            sub_bits,
            h,
            width,
            height,
        }
    }
    /// Sample columns across the image.
    pub fn sw(&self) -> usize {
        (self.width * self.n) as usize
    }
    /// Sample rows down the image.
    pub fn sh(&self) -> usize {
        (self.height * self.n) as usize
    }
    /// Samples of the whole screen.
    pub fn samples(&self) -> u64 {
        self.sw() as u64 * self.sh() as u64
    }
    /// Pixels of the whole screen.
    pub fn pixels(&self) -> u64 {
        self.width as u64 * self.height as u64
    }
    /// Sample centre in pixels (float reference).
    #[inline]
    pub fn sample_pos(&self, c: i64) -> f64 {
        (c as f64 + 0.5) / self.n as f64
    }
}

/// A rectangle of pixels, half-open: `[x0, x1) x [y0, y1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Region {
    /// Left.
    pub x0: u32,
    /// Top.
    pub y0: u32,
    /// Right (exclusive).
    pub x1: u32,
    /// Bottom (exclusive).
    pub y1: u32,
}

impl Region {
    /// Whether no pixel is inside.
    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }
    /// Pixels inside.
    pub fn pixels(&self) -> u64 {
        if self.is_empty() {
            0
        } else {
            (self.x1 - self.x0) as u64 * (self.y1 - self.y0) as u64
        }
    }
    /// The whole `width x height` screen.
    pub fn screen(width: u32, height: u32) -> Region {
        Region {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
        }
    }
    /// A pixel box `[x0, y0, x1, y1)` (unclamped) clamped to `screen` (whose origin is 0).
    pub fn of_box(b: &[i64; 4], screen: &Region) -> Region {
        let cx = |v: i64| v.clamp(0, screen.x1 as i64) as u32;
        let cy = |v: i64| v.clamp(0, screen.y1 as i64) as u32;
        Region {
            x0: cx(b[0]),
            y0: cy(b[1]),
            x1: cx(b[2]),
            y1: cy(b[3]),
        }
    }
    /// The union of pixel boxes (primitives' footprints), clipped to `screen` (empty when
    /// there is none or it lies off the screen).
    pub fn bounding(boxes: &[[i64; 4]], screen: &Region) -> Region {
        let Some(first) = boxes.first() else {
            return Region::default();
        };
        let u = boxes.iter().fold(*first, |a, b| {
            [
                a[0].min(b[0]),
                a[1].min(b[1]),
                a[2].max(b[2]),
                a[3].max(b[3]),
            ]
        });
        let r = Region::of_box(&u, screen);
        if r.is_empty() { Region::default() } else { r }
    }
    /// The intersection with `b` (empty when they do not meet).
    pub fn clip(&self, b: &Region) -> Region {
        let r = Region {
            x0: self.x0.max(b.x0),
            y0: self.y0.max(b.y0),
            x1: self.x1.min(b.x1),
            y1: self.y1.min(b.y1),
        };
        if r.is_empty() { Region::default() } else { r }
    }
}

/// The rectangle of samples a render keeps, half-open, in global sample coordinates
/// (may extend past the screen by the filter's apron).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SampleRegion {
    /// First column.
    pub c0: i64,
    /// First row.
    pub k0: i64,
    /// One past the last column.
    pub c1: i64,
    /// One past the last row.
    pub k1: i64,
}

impl SampleRegion {
    /// Columns.
    pub fn width(&self) -> usize {
        (self.c1 - self.c0).max(0) as usize
    }
    /// Rows.
    pub fn height(&self) -> usize {
        (self.k1 - self.k0).max(0) as usize
    }
    /// Samples.
    pub fn len(&self) -> usize {
        self.width() * self.height()
    }
    /// Whether empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Buffer index of a sample inside the region.
    #[inline]
    pub fn index(&self, c: i64, k: i64) -> usize {
        (k - self.k0) as usize * self.width() + (c - self.c0) as usize
    }
}

/// The plan's tile map: square tiles of `size` pixels over the screen, each either binned
/// (a primitive's bounding box, widened by the filter apron, meets it inside the region) or
/// not. The accumulate stage computes the pixels of binned tiles only; every other pixel
/// sees background samples only and takes the background code (a per-tile "background"
/// flag, like a fast clear); the cycle model has one pixel-chain token per binned tile.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Tiles {
    /// Tile size in pixels.
    pub size: u32,
    /// Tile columns.
    pub cols: u32,
    /// Tile rows.
    pub rows: u32,
    /// Screen width, pixels.
    pub width: u32,
    /// Screen height, pixels.
    pub height: u32,
    /// Binned flags, row-major.
    pub touched: Vec<bool>,
}

impl Tiles {
    /// No tile binned.
    pub fn new(size: u32, width: u32, height: u32) -> Self {
        let (cols, rows) = (width.div_ceil(size), height.div_ceil(size));
        Self {
            size,
            cols,
            rows,
            width,
            height,
            touched: vec![false; cols as usize * rows as usize],
        }
    }

    /// Index of the tile holding pixel `(px, py)`.
    #[inline]
    pub fn index(&self, px: u32, py: u32) -> usize {
        (py / self.size * self.cols + px / self.size) as usize
    }

    /// Whether the tile of pixel `(px, py)` is binned.
    #[inline]
    pub fn is_touched(&self, px: u32, py: u32) -> bool {
        self.touched[self.index(px, py)]
    }

    /// Binned tiles.
    pub fn count(&self) -> usize {
        self.touched.iter().filter(|&&t| t).count()
    }

    /// Pixels of tile `t` (clipped to the screen).
    pub fn rect(&self, t: usize) -> Region {
        let (tx, ty) = (t as u32 % self.cols, t as u32 / self.cols);
        Region {
            x0: tx * self.size,
            y0: ty * self.size,
            x1: ((tx + 1) * self.size).min(self.width),
            y1: ((ty + 1) * self.size).min(self.height),
        }
    }

    /// Pixels of binned tiles that are inside `region`.
    pub fn touched_pixels(&self, region: &Region) -> u64 {
        self.binned_in(region).map(|(_, r)| r.pixels()).sum()
    }

    /// The binned tiles that meet `region`, row-major, with their pixels inside it.
    pub fn binned_in<'a>(
        &'a self,
        region: &'a Region,
    ) -> impl Iterator<Item = (usize, Region)> + 'a {
        (0..self.touched.len())
            .filter(|&t| self.touched[t])
            .map(|t| (t, self.rect(t).clip(region)))
            .filter(|(_, r)| !r.is_empty())
    }

    /// The tile rows of pixel rows `y0..y1` (`y0` a multiple of the tile size) as a tile map
    /// of a `width x (y1 - y0)` screen: a band of a banded run, shifted to row 0.
    pub fn band(&self, y0: u32, y1: u32) -> Tiles {
        let rows = (y1 - y0).div_ceil(self.size);
        let first = (y0 / self.size * self.cols) as usize;
        let end = (first + (rows * self.cols) as usize).min(self.touched.len());
        Tiles {
            size: self.size,
            cols: self.cols,
            rows,
            width: self.width,
            height: y1 - y0,
            touched: self.touched[first.min(end)..end].to_vec(),
        }
    }

    /// Marks every tile meeting the pixel box `b` (clipped to `region`).
    pub fn bin(&mut self, b: &Region, region: &Region) {
        self.bin_if(b, region, |_| true);
    }

    /// Marks every tile meeting the pixel box `b` (clipped to `region`) for which `meets`
    /// holds on the tile's pixels inside the box.
    pub fn bin_if(&mut self, b: &Region, region: &Region, meets: impl Fn(&Region) -> bool) {
        let c = b.clip(region);
        if c.is_empty() {
            return;
        }
        for ty in c.y0 / self.size..=(c.y1 - 1) / self.size {
            for tx in c.x0 / self.size..=(c.x1 - 1) / self.size {
                let t = (ty * self.cols + tx) as usize;
                if !self.touched[t] && meets(&self.rect(t).clip(&c)) {
                    self.touched[t] = true;
                }
            }
        }
    }
}

/// Everything the plan fixes about the screen, and the stages it runs, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// The sample grid.
    pub grid: Grid,
    /// Pixels modelled (half-open); the rest is background.
    pub region: Region,
    /// Samples the region's filter windows read.
    pub samples: SampleRegion,
    /// The tile map.
    pub tiles: Tiles,
    /// The planned stages in run order.
    pub order: Vec<StageId>,
    /// The band of pixel rows a banded run is computing (`None`: the whole screen at once).
    /// See [`Band`].
    pub band: Option<Band>,
    /// Intensity channels: 1 (grey) or 3 (R, G, B). The geometry stages (input to
    /// visibility) carry every channel's intensity; the stages after visibility run once per
    /// channel on that channel's samples, with that channel's word widths
    /// ([`crate::config::HwConfig::channel`]).
    pub channels: usize,
}

/// One band of a banded run: the pipeline runs raster, visibility and accumulate band by
/// band so that the sample buffers and fragment lists hold one band, not the screen.
///
/// Raster and visibility see the band's *own* sample rows in `Layout::samples` (the bands'
/// own rows partition the plan's sample region, so every sample is rasterised and resolved
/// once); the accumulate stage sees the band's pixel rows `y0..y1` shifted to row 0, with
/// the sample rows their filter windows read (the rows before the band's own come from the
/// band before), and writes a `width x (y1 - y0)` frame that the runner copies into the
/// whole frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Band {
    /// First pixel row of the band (a multiple of the tile size).
    pub y0: u32,
    /// One past its last pixel row.
    pub y1: u32,
    /// Whether this is the first band: it also counts the rows the raster walks above the
    /// plan's sample region (every later band starts inside it).
    pub first: bool,
}

impl Layout {
    /// The pixel tokens of a post stage (gamma, dither): one per screen row of `width`
    /// pixels when `rows` (after depth of field, which writes the frame row by row, or a
    /// kernel that runs in raster order), else one per binned tile with its pixels inside
    /// the region.
    pub fn pixel_tokens(&self, rows: bool) -> (super::TokenKind, Vec<u64>) {
        if rows {
            let (w, h) = (self.grid.width as u64, self.grid.height as usize);
            (super::TokenKind::Row, vec![w; h])
        } else {
            let t = &self.tiles;
            (
                super::TokenKind::Tile,
                t.binned_in(&self.region).map(|(_, r)| r.pixels()).collect(),
            )
        }
    }

    /// Whether the plan runs `id`.
    pub fn has(&self, id: StageId) -> bool {
        self.order.contains(&id)
    }
    /// The planned stage that runs right after `id`, if any.
    pub fn next(&self, id: StageId) -> Option<StageId> {
        let i = self.order.iter().position(|&s| s == id)?;
        self.order.get(i + 1).copied()
    }
}
