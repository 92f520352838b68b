//! How the per-pixel kernels of the post stages (gamma LUT, ordered dither) spread a frame
//! over the threads: in parts, the calling thread computing the first one itself while the
//! rayon threads take the others. Handing every part to the pool instead makes the caller
//! (the pipeline's main thread, not a pool thread) sleep until the pool is done and wake
//! again, which costs as much as the kernel itself on a 640x480 frame (docs/speed.md).

/// Runs `f` on every part, the first on the calling thread and the rest on rayon threads;
/// returns the results in part order (so a sum of them is the same on any thread count).
pub fn run_parts<P: Send, T: Send>(parts: Vec<P>, f: impl Fn(P) -> T + Sync) -> Vec<T> {
    let mut out: Vec<Option<T>> = (0..parts.len()).map(|_| None).collect();
    let mut todo = parts.into_iter().zip(out.iter_mut());
    let first = todo.next();
    let f = &f;
    rayon::in_place_scope(|s| {
        for (p, slot) in todo {
            s.spawn(move |_| *slot = Some(f(p)));
        }
        if let Some((p, slot)) = first {
            *slot = Some(f(p));
        }
    });
    out.into_iter()
        .map(|r| r.expect("every part ran"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::run_parts;

    #[test]
    fn results_come_back_in_part_order() {
        let parts: Vec<u64> = (0..9).collect();
        assert_eq!(
            run_parts(parts, |p| p * p),
            (0..9).map(|p| p * p).collect::<Vec<_>>()
        );
        assert!(run_parts(Vec::<u8>::new(), |p| p).is_empty());
    }
}
