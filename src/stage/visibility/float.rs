//! The visibility stage's float reference: the float fragments depth-tested without
//! quantisation into a float sample buffer.

use super::BACKGROUND;
use crate::stage::SampleRegion;
use crate::stage::accumulate::PointFrags;
use crate::stage::raster::{FPrim, FragF};
use crate::stage::taps::{Frags, PrimsF, SampleTapF};

/// The float sample buffer.
#[derive(Clone, Debug, PartialEq)]
pub struct SamplesF {
    /// Region covered.
    pub reg: SampleRegion,
    /// Depth in input z-format LSBs; `inf` is "nothing".
    pub z: Vec<f64>,
    /// Winning primitive id.
    pub prim: Vec<u32>,
    /// Intensity in intensity-format LSBs.
    pub i: Vec<f64>,
}

impl SamplesF {
    /// A cleared buffer.
    pub fn new(reg: SampleRegion, background_i: f64) -> Self {
        let n = reg.len();
        Self {
            reg,
            z: vec![f64::INFINITY; n],
            prim: vec![BACKGROUND; n],
            i: vec![background_i; n],
        }
    }
}

/// The stage's float reference: the float fragments resolved into a float sample buffer
/// over `reg` (surfaces in primitive order), then the light points' visible samples; one
/// sample tap per channel (`channels` of them, the geometry shared).
pub fn float_samples(
    prims: &PrimsF,
    frags: &Frags<FragF>,
    reg: SampleRegion,
    channels: usize,
) -> Vec<SampleTapF> {
    let mut buf = SamplesF::new(reg, prims.bg[0]);
    let mut extra: Vec<Vec<f64>> = (1..channels)
        .map(|c| vec![prims.bg[c]; reg.len()])
        .collect();
    for (p, f) in prims.f.iter().enumerate() {
        if !f.is_point() {
            for f in frags.of(p) {
                resolve_f64(f, p as u32 + 1, &mut buf, &mut extra);
            }
        }
    }
    let mut points = vec![Vec::new(); channels];
    for (p, f) in prims.f.iter().enumerate() {
        let FPrim::Point { v, .. } = f else {
            continue;
        };
        let vis: Vec<u32> = frags
            .of(p)
            .flat_map(|f| point_visible_f64(f, &buf))
            .map(|v| v.0)
            .collect();
        for (c, pts) in points.iter_mut().enumerate() {
            pts.push(PointFrags {
                i: v.i[c],
                samples: vis.clone(),
            });
        }
    }
    let mut planes = std::iter::once(std::mem::take(&mut buf.i)).chain(extra);
    points
        .into_iter()
        .enumerate()
        .map(|(c, points)| SampleTapF {
            samples: SamplesF {
                reg,
                z: buf.z.clone(),
                prim: buf.prim.clone(),
                i: planes.next().expect("one plane per channel"),
            },
            points,
            bg: prims.bg[c],
        })
        .collect()
}

/// Float reference: depth test without quantisation (channels as in [`resolve`]).
pub fn resolve_f64(frags: &[FragF], prim: u32, buf: &mut SamplesF, extra: &mut [Vec<f64>]) {
    for f in frags {
        let s = f.s as usize;
        if f.z < buf.z[s] {
            buf.z[s] = f.z;
            buf.prim[s] = prim;
            buf.i[s] = f.i[0];
            for (c, plane) in extra.iter_mut().enumerate() {
                plane[s] = f.i[c + 1];
            }
        }
    }
}

/// Float reference of light-point visibility: the visible samples and channel 0's intensity.
pub fn point_visible_f64(frags: &[FragF], buf: &SamplesF) -> Vec<(u32, f64)> {
    frags
        .iter()
        .filter(|f| f.z < buf.z[f.s as usize])
        .map(|f| (f.s, f.i[0]))
        .collect()
}
