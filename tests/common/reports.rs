//! Reports compared field by field, without the fields that differ between runs by design.

use serde_json::Value;

/// Timings and the plan's memory estimate differ between runs by design.
pub fn skipped(key: &str) -> bool {
    key.ends_with("_ms")
        || key.contains("wall")
        || key.contains("per_s")
        || key == "timing"
        || key == "memory"
        || key == "reused"
}

/// Compares two reports: integers and strings exactly, floats to 1e-9 relative.
pub fn same(a: &Value, b: &Value, path: &str) -> Result<(), String> {
    match (a, b) {
        (Value::Object(x), Value::Object(y)) => {
            let kx: Vec<_> = x.keys().filter(|k| !skipped(k)).collect();
            let ky: Vec<_> = y.keys().filter(|k| !skipped(k)).collect();
            if kx != ky {
                return Err(format!("{path}: keys {kx:?} vs {ky:?}"));
            }
            for k in kx {
                same(&x[k], &y[k], &format!("{path}.{k}"))?;
            }
            Ok(())
        }
        (Value::Array(x), Value::Array(y)) => {
            if x.len() != y.len() {
                return Err(format!("{path}: {} vs {} elements", x.len(), y.len()));
            }
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                same(u, v, &format!("{path}[{i}]"))?;
            }
            Ok(())
        }
        (Value::Number(x), Value::Number(y)) if x.is_f64() || y.is_f64() => {
            let (u, v) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if u == v || (u - v).abs() <= 1e-9 * u.abs().max(v.abs()) {
                Ok(())
            } else {
                Err(format!("{path}: {u} vs {v}"))
            }
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{path}: {a} vs {b}")),
    }
}
