//! Ranks with ties (the "average" method of `scipy.stats.rankdata`).

/// 1-based ranks of `x`; tied values share the mean of the ranks they span.
///
/// Ties are exact `==` equality (so `0.0` and `-0.0` tie). Never panics: NaN and ±∞
/// are ordered by [`f64::total_cmp`] and NaNs never tie, but callers that need a
/// meaningful rank should reject non-finite input first, as [`super::spearman`] does.
pub fn ranks(x: &[f64]) -> Vec<f64> {
    ranks_and_ties(x).0
}

/// Ranks plus the size of every tie group larger than one (for tie corrections).
pub(crate) fn ranks_and_ties(x: &[f64]) -> (Vec<f64>, Vec<usize>) {
    let mut order: Vec<usize> = (0..x.len()).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut ranks = vec![0.0; x.len()];
    let mut ties = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        // total_cmp puts -0.0 right before 0.0, so equal values stay adjacent.
        while end < order.len() && x[order[end]] == x[order[start]] {
            end += 1;
        }
        // Positions start..end hold 1-based ranks start+1 ..= end; their mean:
        let shared = (start + 1 + end) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = shared;
        }
        if end - start > 1 {
            ties.push(end - start);
        }
        start = end;
    }
    (ranks, ties)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distinct_values_get_their_positions() {
        assert_eq!(ranks(&[30.0, 10.0, 20.0]), vec![3.0, 1.0, 2.0]);
        assert!(ranks(&[]).is_empty());
        assert_eq!(ranks(&[5.0]), vec![1.0]);
    }

    #[test]
    fn ties_share_the_average_rank() {
        // Sorted: 1, 2, 2, 3, 3, 3 occupy ranks 1..6.
        // The 2s share (2+3)/2 = 2.5; the 3s share (4+5+6)/3 = 5.
        // Same as scipy.stats.rankdata([3, 2, 1, 3, 2, 3]) -> [5, 2.5, 1, 5, 2.5, 5].
        let (r, t) = ranks_and_ties(&[3.0, 2.0, 1.0, 3.0, 2.0, 3.0]);
        assert_eq!(r, vec![5.0, 2.5, 1.0, 5.0, 2.5, 5.0]);
        assert_eq!(t, vec![2, 3]);
        // All tied: every rank is (1+2+3+4)/4 = 2.5.
        assert_eq!(ranks(&[7.0; 4]), vec![2.5; 4]);
    }

    #[test]
    fn signed_zeros_tie_and_non_finite_does_not_panic() {
        assert_eq!(ranks(&[0.0, -0.0, 1.0]), vec![1.5, 1.5, 3.0]);
        let r = ranks(&[f64::NAN, 1.0, f64::INFINITY, f64::NEG_INFINITY]);
        assert_eq!(r, vec![4.0, 2.0, 3.0, 1.0]);
    }
}
