//! Numbers as the CLI shows them. A value that reads as zero never carries a minus sign
//! ("-0.00 mm", "-0" in a CSV; JSON: `jawtrack_session::json::clean_json`): users read the
//! sign as a direction.

pub(crate) use jawtrack_plot::fixed;

/// Parses `count` comma-separated finite numbers (mm), for flags giving points; `what` names
/// them in the error ("LX,LY,LZ,RX,RY,RZ").
pub(crate) fn parse_numbers(s: &str, count: usize, what: &str) -> Result<Vec<f64>, String> {
    let v: Vec<f64> =
        s.split(',').map(|c| c.trim().parse::<f64>().map_err(|e| format!("'{c}': {e}"))).collect::<Result<_, _>>()?;
    if v.len() != count {
        return Err(format!("expected {what} ({count} numbers in mm), got {} numbers", v.len()));
    }
    if v.iter().any(|c| !c.is_finite()) {
        return Err("the coordinates must be finite".into());
    }
    Ok(v)
}

/// Parses a point `X,Y,Z` (mm).
pub(crate) fn parse_point(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3, "X,Y,Z")?;
    Ok([v[0], v[1], v[2]])
}

/// Parses a frame number (its `frame` in the recording), for `--rest-frame`: a negative or
/// fractional one is named as such rather than as "invalid digit".
pub(crate) fn parse_frame(s: &str) -> Result<u64, String> {
    s.trim().parse::<u64>().map_err(|_| format!("expected a frame number (a whole number, 0 or more), got '{s}'"))
}

/// Parses a positive, finite angle in degrees.
pub(crate) fn parse_positive_deg(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive angle in degrees, got '{s}'")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_and_angles_say_what_they_expect() {
        assert_eq!(parse_frame("12"), Ok(12));
        for bad in ["-1", "1.5", "x", ""] {
            assert!(
                parse_frame(bad).is_err_and(|e| e.contains("a whole number, 0 or more") && e.contains(bad)),
                "{bad}"
            );
        }
        assert_eq!(parse_positive_deg("12.5"), Ok(12.5));
        for bad in ["-5", "0", "NaN", "inf", "x"] {
            assert!(parse_positive_deg(bad).is_err_and(|e| e.contains("positive angle") && e.contains(bad)), "{bad}");
        }
    }

    #[test]
    fn numbers_are_counted_and_must_be_finite() {
        assert_eq!(parse_numbers("1, -2.5,3", 3, "X,Y,Z"), Ok(vec![1.0, -2.5, 3.0]));
        assert!(parse_numbers("1,2", 3, "X,Y,Z").is_err_and(|e| e.contains("X,Y,Z") && e.contains("got 2")));
        assert!(parse_numbers("1,inf,2", 3, "X,Y,Z").is_err_and(|e| e.contains("finite")));
        assert!(parse_numbers("1,a,2", 3, "X,Y,Z").is_err_and(|e| e.contains("'a'")));
        assert_eq!(parse_point("1,-2.5, 3"), Ok([1.0, -2.5, 3.0]));
        assert!(parse_point("1,2").is_err_and(|e| e.contains("3 numbers in mm")));
    }
}
