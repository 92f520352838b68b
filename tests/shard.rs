//! `--shard K/N` and `--shard auto` in the library: the shard a Slurm array task or a
//! Kubernetes indexed Job's variables give, whatever the array's first index and step, and
//! the refusal of arrays that do not number shards. The command line's use of them is in
//! tests/merge.rs, the real cluster in tests/slurm.rs.

use igemu::sweep::grid::Shard;
use std::collections::HashMap;

/// `Shard::from_env` over a map of variables.
fn from_env(count: Option<usize>, vars: &[(&str, &str)]) -> Result<Shard, String> {
    let m: HashMap<String, String> = vars
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    Shard::from_env(count, |k| m.get(k).cloned()).map(|(s, _)| s)
}

fn array(id: usize, min: usize, max: usize, count: usize, step: usize) -> Vec<(String, String)> {
    [
        ("SLURM_ARRAY_TASK_ID", id),
        ("SLURM_ARRAY_TASK_MIN", min),
        ("SLURM_ARRAY_TASK_MAX", max),
        ("SLURM_ARRAY_TASK_COUNT", count),
        ("SLURM_ARRAY_TASK_STEP", step),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect()
}

fn slurm(count: Option<usize>, v: &[(String, String)]) -> Result<Shard, String> {
    let v: Vec<(&str, &str)> = v.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    from_env(count, &v)
}

#[test]
fn slurm_arrays_map_to_shards_from_their_first_index_and_step() {
    let sh = |k, n| Ok(Shard { k, n });
    // --array=0-3 and --array=1-4: the same four shards.
    for t in 0..4 {
        assert_eq!(slurm(None, &array(t, 0, 3, 4, 1)), sh(t + 1, 4));
        assert_eq!(slurm(None, &array(t + 1, 1, 4, 4, 1)), sh(t + 1, 4));
        assert_eq!(slurm(Some(4), &array(t, 0, 3, 4, 1)), sh(t + 1, 4));
    }
    // --array=2-8:3 is tasks 2, 5, 8.
    assert_eq!(slurm(None, &array(5, 2, 8, 3, 3)), sh(2, 3));
    assert_eq!(slurm(None, &array(8, 2, 8, 3, 3)), sh(3, 3));
    assert!(
        slurm(None, &array(4, 2, 8, 3, 3))
            .unwrap_err()
            .contains("one of 2, 5, ..., 8")
    );
    // --array=1,3,8 (Slurm says MIN=1 MAX=8 COUNT=3 STEP=1): not a range.
    let e = slurm(None, &array(3, 1, 8, 3, 1)).unwrap_err();
    assert!(e.contains("not a range"), "{e}");
    // A one-task array (a failed task resubmitted alone) would run the whole grid.
    let e = slurm(None, &array(2, 2, 2, 1, 1)).unwrap_err();
    assert!(
        e.contains("one-task array") && e.contains("--shard K/N"),
        "{e}"
    );
    assert_eq!(slurm(Some(1), &array(2, 2, 2, 1, 1)), sh(1, 1));
    let e = slurm(Some(4), &array(2, 2, 2, 1, 1)).unwrap_err();
    assert!(e.contains("has 1 tasks, not 4"), "{e}");
    // Missing or zero counts are named.
    let e = from_env(None, &[("SLURM_ARRAY_TASK_ID", "1")]).unwrap_err();
    assert!(e.contains("SLURM_ARRAY_TASK_MIN is not"), "{e}");
    let e = slurm(None, &array(0, 0, 0, 0, 1)).unwrap_err();
    assert!(e.contains("at least 1"), "{e}");
    // Slurm wins over a Kubernetes index; a Kubernetes index is 0-based.
    let mut both = array(1, 0, 3, 4, 1);
    both.push(("JOB_COMPLETION_INDEX".into(), "3".into()));
    assert_eq!(slurm(None, &both), sh(2, 4));
    assert_eq!(
        from_env(Some(5), &[("JOB_COMPLETION_INDEX", "0")]),
        sh(1, 5)
    );
    // `K/N` still parses as before, and `auto` without any variable is refused.
    let none = |_: &str| None;
    assert_eq!(
        Shard::from_arg("2/4", none),
        Ok((Shard { k: 2, n: 4 }, None))
    );
    assert!(Shard::from_arg("auto", none).is_err());
    assert!(
        Shard::from_arg("auto4", none)
            .unwrap_err()
            .contains("auto/N")
    );
}
