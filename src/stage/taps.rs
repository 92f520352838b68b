//! The taps: the signals between stages, fixed and float side by side. A stage reads the
//! taps of its input and writes its own; every tap is shared (`Arc`), so the taps after a
//! stage are cheap to keep (for per-stage comparison, dumps, test vectors) and a cached
//! stage result costs nothing to reuse.
//!
//! | tap | written by | fixed | float reference |
//! |---|---|---|---|
//! | `host` | the plan (host front end, f64) | | |
//! | `prims` | input | quantised primitives, background code | host primitives in the fixed units |
//! | `setups` | setup | edge and plane constants | (none: the float raster reads the primitives) |
//! | `frags` | raster | covered samples per primitive | the same from the float raster |
//! | `samples` | visibility, logdomain | resolved sample buffer, visible light-point samples | the same in f64 |
//! | `frame` | accumulate, dof | frame memory (codes, depth, coverage) and its coding | frame intensity in frame LSBs |
//! | `channels` | the runner, before a stage reading all channels | every channel's frame | every channel's float frame |
//! | `pixels` | gamma, dither | codes with `frac` fraction bits (the DAC codes at the end) | real values or codes |

use super::accumulate::{Frame, PointFrags};
use super::input::QPrim;
use super::logdomain::{LogAdder, LogCode};
use super::raster::{FPrim, FragF, FragRuns};
use super::setup::Setup;
use super::visibility::{Samples, SamplesF};
use crate::fixed::QFormat;
use crate::scene::HostScene;
use std::sync::{Arc, OnceLock};

/// Every tap after a stage.
#[derive(Clone, Default)]
pub struct Taps {
    /// The host's screen-space primitives (f64).
    pub host: Option<Arc<HostScene>>,
    /// The fixed-point model's taps.
    pub fixed: FixedTaps,
    /// The float reference's taps.
    pub float: FloatTaps,
    /// The channel of a colour render's lane these taps belong to (0 R, 1 G, 2 B; 0 before
    /// the lanes split and for a grey render).
    pub lane: usize,
    /// Every channel's frame, set by the runner before a stage that reads all channels of a
    /// colour render ([`crate::stage::Stage::reads_channels`]) and dropped after it.
    pub channels: Option<Arc<ChannelFrames>>,
}

/// Every channel's frame before a stage that reads all channels (the luminance-aware DoF
/// of a colour render weighs its blur by the luminance of R, G and B).
pub struct ChannelFrames {
    /// The channel of the lane these taps belong to (0 R, 1 G, 2 B).
    pub lane: usize,
    /// Each channel's fixed frame memory.
    pub fixed: Vec<Arc<FrameTap>>,
    /// Each channel's float frame, in its frame LSBs (`None` on the fixed-only path).
    pub float: Option<Vec<Arc<Vec<f64>>>>,
    /// Each channel's frame word.
    pub formats: Vec<QFormat>,
}

/// Taps of the fixed-point model.
#[derive(Clone, Default)]
pub struct FixedTaps {
    /// Quantised primitives (input).
    pub prims: Option<Arc<Prims>>,
    /// Per-primitive setup (setup).
    pub setups: Option<Arc<Vec<Setup>>>,
    /// Covered samples per primitive (raster), as runs.
    pub frags: Option<Arc<FragRuns>>,
    /// The sample buffer (visibility; logdomain re-codes it): channel 0's.
    pub samples: Option<Arc<SampleTap>>,
    /// The sample buffers of channels 1.. of a colour render (visibility); the runner
    /// moves each into its own lane of taps ([`Taps::lane`]).
    pub more_samples: Vec<Arc<SampleTap>>,
    /// The frame memory (accumulate; dof replaces its codes).
    pub frame: Option<Arc<FrameTap>>,
    /// Pixel codes after the gamma LUT or the dither.
    pub pixels: Option<Arc<PixelTap>>,
}

/// Taps of the float reference.
#[derive(Clone, Default)]
pub struct FloatTaps {
    /// Host primitives in the fixed formats' units, unrounded.
    pub prims: Option<Arc<PrimsF>>,
    /// Covered samples per primitive.
    pub frags: Option<Arc<Frags<FragF>>>,
    /// The sample buffer: channel 0's.
    pub samples: Option<Arc<SampleTapF>>,
    /// The sample buffers of channels 1.. of a colour render.
    pub more_samples: Vec<Arc<SampleTapF>>,
    /// Frame intensity in frame LSBs.
    pub frame: Option<Arc<Vec<f64>>>,
    /// A key of `frame`'s content finer than the key of the stage that wrote it, where that
    /// stage knows one (the layered depth of field's float, the same for every datapath
    /// width of one layer plan); `None`: the writing stage's key. Every stage that writes
    /// `frame` sets it. Values derived from the float frame alone are memoised by
    /// [`FloatTaps::frame_key`].
    pub frame_content: Option<u64>,
    /// Pixel values after the gamma curve or the dither.
    pub pixels: Option<Arc<PixelTapF>>,
}

fn need<'a, T>(t: &'a Option<Arc<T>>, what: &str) -> &'a T {
    t.as_deref()
        .unwrap_or_else(|| panic!("plan error: no {what} tap (a stage runs before its input)"))
}

impl Taps {
    /// The host scene.
    pub fn host(&self) -> &HostScene {
        need(&self.host, "host")
    }

    /// The taps of channel `c`'s lane after visibility: these taps with channel `c`'s
    /// sample buffers as the sample taps (the stages after visibility run once per channel
    /// on them).
    pub fn lane(&self, c: usize) -> Taps {
        let mut t = self.clone();
        t.lane = c;
        if c > 0 {
            t.fixed.samples = Some(self.fixed.more_samples[c - 1].clone());
            // No float sample buffers on the fixed-only path.
            t.float.samples = self.float.more_samples.get(c - 1).cloned();
        }
        t.fixed.more_samples.clear();
        t.float.more_samples.clear();
        t
    }
}

impl FixedTaps {
    /// The quantised primitives.
    pub fn prims(&self) -> &Prims {
        need(&self.prims, "fixed prims")
    }
    /// The setups.
    pub fn setups(&self) -> &[Setup] {
        need(&self.setups, "setups").as_slice()
    }
    /// The fragments.
    pub fn frags(&self) -> &FragRuns {
        need(&self.frags, "fixed frags")
    }
    /// The sample buffer.
    pub fn samples(&self) -> &SampleTap {
        need(&self.samples, "fixed samples")
    }
    /// The frame memory.
    pub fn frame(&self) -> &FrameTap {
        need(&self.frame, "fixed frame")
    }
    /// The pixel codes.
    pub fn pixels(&self) -> &PixelTap {
        need(&self.pixels, "fixed pixels")
    }
}

impl FloatTaps {
    /// The key of the float frame's content: [`FloatTaps::frame_content`], else `stage_key`
    /// (the key of the stage that wrote it: the next stage's input key).
    pub fn frame_key(&self, stage_key: u64) -> u64 {
        self.frame_content.unwrap_or(stage_key)
    }
    /// The float primitives.
    pub fn prims(&self) -> &PrimsF {
        need(&self.prims, "float prims")
    }
    /// The float fragments.
    pub fn frags(&self) -> &Frags<FragF> {
        need(&self.frags, "float frags")
    }
    /// The float sample buffer.
    pub fn samples(&self) -> &SampleTapF {
        need(&self.samples, "float samples")
    }
    /// The float frame.
    pub fn frame(&self) -> &[f64] {
        need(&self.frame, "float frame").as_slice()
    }
    /// The float pixels.
    pub fn pixels(&self) -> &PixelTapF {
        need(&self.pixels, "float pixels")
    }
}

/// The quantised primitives and the background's intensity code.
#[derive(Clone, Debug, PartialEq)]
pub struct Prims {
    /// Primitives in scene order.
    pub q: Vec<QPrim>,
    /// Background intensity code per channel (quantised like a vertex intensity).
    pub bg: [u32; 3],
}

/// The float reference's primitives and background.
#[derive(Clone, Debug)]
pub struct PrimsF {
    /// Primitives in scene order, in the fixed formats' units.
    pub f: Vec<FPrim>,
    /// Background intensity per channel (intensity LSBs).
    pub bg: [f64; 3],
}

/// The order the geometry stages process primitives in: surfaces in scene order, then light
/// points (they are added to the frame after every surface is resolved).
pub fn processing_order(is_point: impl Fn(usize) -> bool, n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).filter(|&i| !is_point(i)).collect();
    order.extend((0..n).filter(|&i| is_point(i)));
    order
}

/// Where one primitive's fragments sit in a part of a [`Frags`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Span {
    /// The primitive (its index in scene order).
    pub prim: u32,
    /// First fragment of the part's list.
    pub a: usize,
    /// One past its last fragment.
    pub b: usize,
}

/// Per-primitive fragment lists, in the order the raster emitted them, held in parts: the
/// fixed raster writes one part per few sample rows (every primitive's fragments in
/// those rows, in primitive order), so each part of the sample buffer reads its own part
/// alone; the float raster writes one part. A primitive's fragments are its pieces in part
/// order. Two lists are equal when every primitive's fragments are, however they are split.
#[derive(Clone, Debug, Default)]
pub struct Frags<T> {
    /// The fragments, part by part.
    pub parts: Vec<Vec<T>>,
    /// Per part, in primitive order: the primitives with fragments in it and their ranges.
    pub spans: Vec<Vec<Span>>,
    /// Per part: the sample indices its fragments fall in (`start..end`; disjoint and in
    /// order for row bands, everything for one part).
    pub bounds: Vec<(usize, usize)>,
    /// Primitives listed.
    pub prims: usize,
    /// Every primitive's pieces, built on the first [`Frags::of`] (the lists do not change
    /// once built).
    pub index: OnceLock<PieceIndex>,
}

/// The pieces of a [`Frags`] by primitive: primitive `p`'s are
/// `pieces[start[p]..start[p + 1]]`, each `(part, span)` in part order (one pass over the
/// spans, then a counting sort by primitive).
#[derive(Clone, Debug, Default)]
pub struct PieceIndex {
    start: Vec<u32>,
    pieces: Vec<(u32, u32)>,
}

impl PieceIndex {
    fn new(spans: &[Vec<Span>], prims: usize) -> Self {
        let mut start = vec![0u32; prims + 1];
        for sp in spans.iter().flatten() {
            start[sp.prim as usize + 1] += 1;
        }
        for p in 0..prims {
            start[p + 1] += start[p];
        }
        let mut next = start.clone();
        let mut pieces = vec![(0, 0); start[prims] as usize];
        for (part, list) in spans.iter().enumerate() {
            for (j, sp) in list.iter().enumerate() {
                let at = &mut next[sp.prim as usize];
                pieces[*at as usize] = (part as u32, j as u32);
                *at += 1;
            }
        }
        Self { start, pieces }
    }
}

impl<T> Frags<T> {
    /// One part holding the lists emitted by `emit(p, out)` for every primitive `p < n`, in
    /// order.
    pub fn one_part(n: usize, data: Vec<T>, mut emit: impl FnMut(usize, &mut Vec<T>)) -> Self {
        let mut data = data;
        let mut spans = Vec::with_capacity(n);
        for p in 0..n {
            let a = data.len();
            emit(p, &mut data);
            if data.len() > a {
                spans.push(Span {
                    prim: p as u32,
                    a,
                    b: data.len(),
                });
            }
        }
        Self {
            parts: vec![data],
            spans: vec![spans],
            bounds: vec![(0, usize::MAX)],
            prims: n,
            index: OnceLock::new(),
        }
    }

    /// Primitive `p`'s fragments, piece by piece (one piece per part it has fragments in).
    pub fn of(&self, p: usize) -> impl Iterator<Item = &[T]> + '_ {
        let index = self
            .index
            .get_or_init(|| PieceIndex::new(&self.spans, self.prims));
        let range = match index.start.get(p..p + 2) {
            Some(&[a, b]) => a as usize..b as usize,
            _ => 0..0,
        };
        index.pieces[range].iter().map(move |&(part, j)| {
            let s = self.spans[part as usize][j as usize];
            &self.parts[part as usize][s.a..s.b]
        })
    }

    /// The number of primitive `p`'s fragments.
    pub fn count(&self, p: usize) -> usize {
        self.of(p).map(<[T]>::len).sum()
    }

    /// Fragments of all primitives.
    pub fn len(&self) -> usize {
        self.parts.iter().map(Vec::len).sum()
    }

    /// Whether no primitive has a fragment.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl<T: PartialEq> PartialEq for Frags<T> {
    fn eq(&self, o: &Self) -> bool {
        self.prims == o.prims && (0..self.prims).all(|p| self.of(p).flatten().eq(o.of(p).flatten()))
    }
}

/// How the sample buffer codes intensity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SampleCoding {
    /// Linear intensity codes.
    Linear,
    /// Log codes (structure b: the accumulate stage adds them in the log domain).
    Log(LogCode),
}

/// The fixed sample buffer.
#[derive(Clone, Debug)]
pub struct SampleTap {
    /// Resolved samples (depth, intensity, primitive id).
    pub samples: Samples,
    /// Light points: intensity code and visible samples.
    pub points: Vec<PointFrags<u32>>,
    /// Background intensity code (what an empty sample holds).
    pub bg: u32,
    /// Intensity coding.
    pub coding: SampleCoding,
}

/// The float sample buffer.
#[derive(Clone, Debug)]
pub struct SampleTapF {
    /// Resolved samples.
    pub samples: SamplesF,
    /// Light points.
    pub points: Vec<PointFrags<f64>>,
    /// Background intensity.
    pub bg: f64,
}

/// How the frame memory codes intensity.
#[derive(Clone, Debug)]
pub enum FrameCoding {
    /// Linear codes of the `accumulate.frame` format.
    Linear,
    /// Log codes of the Gaussian-log adder (structure b).
    Log(Arc<LogAdder>),
}

/// The fixed frame memory.
#[derive(Clone, Debug)]
pub struct FrameTap {
    /// Codes, nearest depth and coverage per pixel.
    pub frame: Frame,
    /// Coding of the codes.
    pub coding: FrameCoding,
}

/// Pixel codes with `frac` fraction bits in `0..=max` (after the gamma LUT or the dither).
///
/// The gamma LUT before an ordered dither leaves its codes as a [`LutRead`] (the frame and
/// the table) rather than a plane: the dither then looks them up row by row in its own
/// pass (`stage::dither`), so the LUT's plane never goes to memory. Whoever else reads
/// the codes ([`PixelTap::codes`]: a dump, the stage-local comparisons, a run stopped
/// after gamma) gets them looked up once, on first read: the same codes either way.
#[derive(Clone, Debug)]
pub struct PixelTap {
    /// Codes, row-major over the screen (set, or looked up on first read from `lut`).
    codes: OnceLock<Vec<u32>>,
    /// Where the codes come from when they were not written as a plane.
    lut: Option<LutRead>,
    /// Fraction bits (0: integer codes, e.g. the DAC codes).
    pub frac: u32,
    /// Largest code.
    pub max: u32,
}

/// Pixel codes not written as a plane: `table[min(acc[i] >> shift, len - 1)]` over the
/// frame memory's codes `acc` ([`crate::stage::gamma::lookup`]).
#[derive(Clone, Debug)]
pub struct LutRead {
    /// The frame the LUT reads.
    pub frame: Arc<FrameTap>,
    /// The LUT.
    pub table: Arc<Vec<u32>>,
    /// The frame's fraction bits the address drops.
    pub shift: u32,
}

impl LutRead {
    /// The frame codes the LUT is addressed by.
    pub fn acc(&self) -> &[u32] {
        &self.frame.frame.acc
    }
}

impl PixelTap {
    /// A plane of codes.
    pub fn new(codes: Vec<u32>, frac: u32, max: u32) -> Self {
        Self {
            codes: OnceLock::from(codes),
            lut: None,
            frac,
            max,
        }
    }

    /// Codes a LUT gives the frame, looked up when first read.
    pub fn deferred(lut: LutRead, frac: u32, max: u32) -> Self {
        Self {
            codes: OnceLock::new(),
            lut: Some(lut),
            frac,
            max,
        }
    }

    /// The codes, row-major (a deferred tap's are looked up on the first call).
    pub fn codes(&self) -> &[u32] {
        self.codes.get_or_init(|| {
            let l = self
                .lut
                .as_ref()
                .expect("a tap without codes has a LUT read");
            let mut codes = vec![0u32; l.acc().len()];
            crate::stage::gamma::lookup(&l.table, l.acc(), l.shift, &mut codes);
            codes
        })
    }

    /// The codes if they are a plane already (written, or looked up by an earlier read).
    pub fn ready(&self) -> Option<&[u32]> {
        self.codes.get().map(Vec::as_slice)
    }

    /// The LUT read of a deferred tap.
    pub fn lut(&self) -> Option<&LutRead> {
        self.lut.as_ref()
    }

    /// The tap's planes, for the pool: its codes (if any were made) and the frame of its
    /// LUT read.
    pub fn into_planes(self) -> (Option<Vec<u32>>, Option<Arc<FrameTap>>) {
        (self.codes.into_inner(), self.lut.map(|l| l.frame))
    }
}

impl PartialEq for PixelTap {
    /// The same codes (deferred or not), fraction bits and largest code.
    fn eq(&self, o: &Self) -> bool {
        self.frac == o.frac && self.max == o.max && self.codes() == o.codes()
    }
}

impl Eq for PixelTap {}

/// Float pixels.
#[derive(Clone, Debug, PartialEq)]
pub enum PixelTapF {
    /// Real values in output LSBs (before a dither quantises them).
    Values(Vec<f64>),
    /// Integer codes.
    Codes(Vec<u32>),
}

/// The pixel planes a stage's output taps hold, for dumps: the frame memory's codes, depth
/// and coverage after accumulate and dof, the pixel codes after gamma and dither.
pub fn image_planes(id: crate::stage_id::StageId) -> &'static [&'static str] {
    use crate::stage_id::StageId;
    match id {
        StageId::Accumulate | StageId::Dof => &["frame", "depth", "coverage"],
        StageId::Gamma | StageId::Dither => &["codes"],
        _ => &[],
    }
}

impl Taps {
    /// A pixel plane of the taps as codes (one per screen pixel): `frame` (frame codes),
    /// `depth` (the nearest depth code's top 16 of 24 bits, 65535 for the background only),
    /// `coverage` (covered samples), `codes` (the pixel codes).
    pub fn image(&self, plane: &str) -> Option<Vec<u32>> {
        match plane {
            "frame" => Some(self.fixed.frame.as_ref()?.frame.acc.clone()),
            "depth" => Some(
                self.fixed
                    .frame
                    .as_ref()?
                    .frame
                    .depth
                    .iter()
                    .map(|&z| if z == u32::MAX { 65535 } else { z >> 8 })
                    .collect(),
            ),
            "coverage" => Some(
                self.fixed
                    .frame
                    .as_ref()?
                    .frame
                    .coverage
                    .iter()
                    .map(|&c| c as u32)
                    .collect(),
            ),
            "codes" => Some(self.fixed.pixels.as_ref()?.codes().to_vec()),
            _ => None,
        }
    }
}
