//! Small analysis helpers of the studies: least-squares convergence order, Pareto front,
//! zero crossings.

/// Least-squares slope and intercept of ln(error) against ln(h): error ≈ C h^order.
/// Points with a non-positive or non-finite h or error are left out; None with fewer
/// than two points left or no spread in h.
pub fn convergence_order(h: &[f64], error: &[f64]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = h
        .iter()
        .zip(error)
        .filter(|(h, e)| **h > 0.0 && **e > 0.0 && h.is_finite() && e.is_finite())
        .map(|(h, e)| (h.ln(), e.ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    Some((slope, (my - slope * mx).exp()))
}

/// Indices of the Pareto-optimal points (lower cost and lower error are better): a point
/// is kept when no other point is at least as good in both and better in one. Sorted by
/// cost.
pub fn pareto_front(cost: &[f64], error: &[f64]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..cost.len())
        .filter(|&i| cost[i].is_finite() && error[i].is_finite())
        .collect();
    idx.sort_by(|&a, &b| {
        cost[a]
            .total_cmp(&cost[b])
            .then(error[a].total_cmp(&error[b]))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in idx {
        if error[i] < best {
            front.push(i);
            best = error[i];
        }
    }
    front
}

/// Times where a sampled signal changes sign, by linear interpolation between samples
/// (sub-step resolution).
pub fn zero_crossings(t: &[f64], u: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for i in 1..u.len().min(t.len()) {
        if u[i - 1] != 0.0 && u[i - 1].signum() != u[i].signum() {
            out.push(t[i - 1] + (t[i] - t[i - 1]) * u[i - 1] / (u[i - 1] - u[i]));
        }
    }
    out
}

/// Period from zero crossings: successive crossings are half a period apart; the least-
/// squares slope of crossing time against index is used (robust to the first crossing's
/// phase offset). None with fewer than 3 crossings.
pub fn period_from_crossings(crossings: &[f64]) -> Option<f64> {
    if crossings.len() < 3 {
        return None;
    }
    let n = crossings.len() as f64;
    let mi = (n - 1.0) / 2.0;
    let mt = crossings.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, t) in crossings.iter().enumerate() {
        sxy += (i as f64 - mi) * (t - mt);
        sxx += (i as f64 - mi).powi(2);
    }
    Some(2.0 * sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_of_synthetic_data() {
        let h = [0.1, 0.05, 0.025, 0.0125];
        let e: Vec<f64> = h.iter().map(|h| 3.0 * h * h).collect();
        let (order, c) = convergence_order(&h, &e).unwrap();
        assert!((order - 2.0).abs() < 1e-12 && (c - 3.0).abs() < 1e-10);
        // Mixed first and second order terms give something in between.
        let e: Vec<f64> = h.iter().map(|h| h + 10.0 * h * h).collect();
        let (order, _) = convergence_order(&h, &e).unwrap();
        assert!(order > 1.0 && order < 2.0, "{order}");
        // Zero errors are left out, one point is not enough.
        assert!(convergence_order(&[0.1, 0.2], &[0.0, 1.0]).is_none());
    }

    #[test]
    fn pareto() {
        let cost = [1.0, 2.0, 3.0, 2.5, 0.5];
        let err = [0.5, 0.2, 0.1, 0.3, 0.9];
        assert_eq!(pareto_front(&cost, &err), vec![4, 0, 1, 2]);
    }

    #[test]
    fn crossings_and_period() {
        let t: Vec<f64> = (0..2000).map(|i| i as f64 * 0.0137).collect();
        let u: Vec<f64> = t
            .iter()
            .map(|t| (2.0 * std::f64::consts::PI * t / 3.3).sin())
            .collect();
        let zc = zero_crossings(&t, &u);
        let p = period_from_crossings(&zc).unwrap();
        assert!((p / 3.3 - 1.0).abs() < 1e-4, "{p}");
    }
}
