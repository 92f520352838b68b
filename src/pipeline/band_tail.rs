//! The rows a band's filter windows read before its own: the kept tail of the band before
//! ([`super::bands`]), joined with a band's own sample buffers, and trimmed to what the next
//! band reads (the part a sequence's cache keeps with the band).

use crate::stage::SampleRegion;
use crate::stage::accumulate::PointFrags;
use crate::stage::taps::{SampleTap, SampleTapF};
use crate::stage::visibility::{Samples, SamplesF};
use std::sync::Arc;

/// The rows `k0..` the next band's filter windows may still read: the previous band's
/// accumulate input.
#[derive(Clone)]
pub(super) struct Tail {
    pub(super) k0: i64,
    pub(super) fixed: Arc<SampleTap>,
    /// `None` on the fixed-only path.
    pub(super) float: Option<Arc<SampleTapF>>,
}

fn join_points<T: Copy>(
    tail: Option<(&[PointFrags<T>], usize)>,
    band: &[PointFrags<T>],
    shift: usize,
) -> Vec<PointFrags<T>> {
    band.iter()
        .enumerate()
        .map(|(j, p)| {
            let mut samples = Vec::new();
            if let Some((t, skip)) = tail {
                samples.extend(
                    t[j].samples
                        .iter()
                        .filter(|&&s| s as usize >= skip)
                        .map(|&s| s - skip as u32),
                );
            }
            samples.extend(p.samples.iter().map(|&s| s + shift as u32));
            PointFrags { i: p.i, samples }
        })
        .collect()
}

/// Joins the kept rows `read..own.0` of `tail` with the band's own buffers: the sample
/// buffer the band's filter windows read, its rows shifted up by `dk` (the band's frame
/// starts at row 0).
pub(super) fn join(
    tail: Option<&Tail>,
    read: i64,
    dk: i64,
    own: &SampleTap,
    own_f: Option<&SampleTapF>,
) -> Tail {
    let reg = own.samples.reg;
    let w = reg.width();
    let kept = (reg.k0 - read) as usize * w;
    let skip = tail.map_or(0, |t| (read - t.k0) as usize * w);
    let joined = SampleRegion {
        k0: read - dk,
        k1: reg.k1 - dk,
        ..reg
    };
    fn cat<T: Copy>(a: Option<&[T]>, skip: usize, kept: usize, b: &[T]) -> Vec<T> {
        let mut v = Vec::with_capacity(kept + b.len());
        if let Some(a) = a {
            v.extend_from_slice(&a[skip..skip + kept]);
        }
        v.extend_from_slice(b);
        v
    }
    let ts = tail.map(|t| &t.fixed.samples);
    let fixed = SampleTap {
        samples: Samples {
            reg: joined,
            z: cat(ts.map(|s| s.z.as_slice()), skip, kept, &own.samples.z).into(),
            prim: cat(ts.map(|s| s.prim.as_slice()), skip, kept, &own.samples.prim).into(),
            i: cat(ts.map(|s| s.i.as_slice()), skip, kept, &own.samples.i),
        },
        points: join_points(
            tail.map(|t| (t.fixed.points.as_slice(), skip)),
            &own.points,
            kept,
        ),
        bg: own.bg,
        coding: own.coding,
    };
    let float = own_f.map(|own_f| {
        let tf = tail.and_then(|t| t.float.as_ref()).map(|f| &f.samples);
        SampleTapF {
            samples: SamplesF {
                reg: joined,
                z: cat(tf.map(|s| s.z.as_slice()), skip, kept, &own_f.samples.z),
                prim: cat(
                    tf.map(|s| s.prim.as_slice()),
                    skip,
                    kept,
                    &own_f.samples.prim,
                ),
                i: cat(tf.map(|s| s.i.as_slice()), skip, kept, &own_f.samples.i),
            },
            points: join_points(
                tail.and_then(|t| t.float.as_ref())
                    .map(|f| (f.points.as_slice(), skip)),
                &own_f.points,
                kept,
            ),
            bg: own_f.bg,
        }
    });
    Tail {
        k0: read,
        fixed: Arc::new(fixed),
        float: float.map(Arc::new),
    }
}

impl Tail {
    /// The rows from `k0` on.
    pub(super) fn from(&self, k0: i64) -> Tail {
        let w = self.fixed.samples.reg.width();
        let skip = (k0 - self.k0).max(0) as usize * w;
        fn points<T: Copy>(p: &[PointFrags<T>], skip: usize) -> Vec<PointFrags<T>> {
            p.iter()
                .map(|p| PointFrags {
                    i: p.i,
                    samples: p
                        .samples
                        .iter()
                        .filter(|&&s| s as usize >= skip)
                        .map(|&s| s - skip as u32)
                        .collect(),
                })
                .collect()
        }
        let s = &self.fixed.samples;
        let reg = SampleRegion {
            k0: s.reg.k0 + (k0 - self.k0).max(0),
            ..s.reg
        };
        let fixed = SampleTap {
            samples: Samples {
                reg,
                z: s.z[skip..].to_vec().into(),
                prim: s.prim[skip..].to_vec().into(),
                i: s.i[skip..].to_vec(),
            },
            points: points(&self.fixed.points, skip),
            bg: self.fixed.bg,
            coding: self.fixed.coding,
        };
        let float = self.float.as_ref().map(|f| {
            let s = &f.samples;
            Arc::new(SampleTapF {
                samples: SamplesF {
                    reg,
                    z: s.z[skip..].to_vec(),
                    prim: s.prim[skip..].to_vec(),
                    i: s.i[skip..].to_vec(),
                },
                points: points(&f.points, skip),
                bg: f.bg,
            })
        });
        Tail {
            k0: self.k0.max(k0),
            fixed: Arc::new(fixed),
            float,
        }
    }
}
