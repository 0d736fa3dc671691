//! The robust statistics estimation and its reports share: one definition of the median for
//! outlier limits, focus distances, error summaries and benchmark timings.

/// The median of `values`: the upper middle value once sorted (NaN sorts above every number),
/// so it is always one of the values; `None` when there are none.
pub fn median(values: impl IntoIterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.into_iter().collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_is_the_upper_middle_value() {
        assert_eq!(median([3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median([4.0, 1.0, 3.0, 2.0]), Some(3.0), "upper middle, a value of the set");
        assert_eq!(median([]), None);
        assert_eq!(median([1.0, f64::NAN, 2.0]), Some(2.0), "NaN sorts last");
    }
}
