//! JSON as the commands write it. A value that reads as zero never carries a minus sign (-0.0
//! in JSON): users read the sign as a direction.

use serde_json::Value;

/// `v` with every -0.0 in it made 0.0.
pub fn clean_json(v: &mut Value) {
    match v {
        Value::Number(n) if n.as_f64().is_some_and(|x| x == 0.0 && x.is_sign_negative()) => *v = Value::from(0.0),
        Value::Array(a) => a.iter_mut().for_each(clean_json),
        Value::Object(o) => o.values_mut().for_each(clean_json),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_has_no_sign_and_everything_else_keeps_its_own() {
        let mut v = serde_json::json!({"a": -0.0, "b": [-0.0, -1.0, 3], "c": "-0.0"});
        clean_json(&mut v);
        assert_eq!(v.to_string(), r#"{"a":0.0,"b":[0.0,-1.0,3],"c":"-0.0"}"#);
    }
}
