//! The spacing's witness (`docs/defaults.md`, `mls_core::normals::spacing_statistics` and
//! `suggest_h`): every distance between distinct positions computed and sorted (mls-core uses
//! a k-d tree on positions centred on their bounding box), the square grid's calibration
//! counted shell by shell (mls-core sorts the nodes of a square), the median of the local
//! spacings, and `h = factor × median`.

use nalgebra::Point3;

/// The witness's spacing of a cloud.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpacingWitness {
    /// The median local spacing.
    pub spacing: f64,
    /// Neighbours used: the requested k, at most the distinct positions less one.
    pub k: usize,
    /// Distinct positions.
    pub distinct: usize,
    /// `factor × spacing`.
    pub h: f64,
}

/// The spacing of `points` with `k` neighbours, and `h = factor × spacing`; `None` for `k = 0`
/// or fewer than two distinct positions.
///
/// For each distinct position p with squared distances `d_1² ≤ … ≤ d_k²` to its k nearest
/// other distinct positions, `s(p) = √(Σ d_j² / k) / ρ_k`, where ρ_k is the same root mean
/// square on the square grid of unit pitch ([`grid_rms_by_shells`]); the spacing is the median
/// of s(p), the mean of the two middle values for an even count.
pub fn spacing_witness(points: &[Point3<f64>], k: usize, factor: f64) -> Option<SpacingWitness> {
    if k == 0 {
        return None;
    }
    // Exact duplicates removed, comparing values (so −0.0 repeats 0.0), first one kept.
    let mut distinct: Vec<Point3<f64>> = Vec::with_capacity(points.len());
    for p in points {
        if !distinct.iter().any(|q| q == p) {
            distinct.push(*p);
        }
    }
    if distinct.len() < 2 {
        return None;
    }
    let k = k.min(distinct.len() - 1);
    let rho = grid_rms_by_shells(k);
    let mut local: Vec<f64> = distinct
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut d2: Vec<f64> = distinct
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (q - p).norm_squared())
                .collect();
            d2.sort_by(f64::total_cmp);
            (d2[..k].iter().sum::<f64>() / k as f64).sqrt() / rho
        })
        .collect();
    local.sort_by(f64::total_cmp);
    let m = local.len();
    let spacing = if m % 2 == 1 {
        local[m / 2]
    } else {
        0.5 * (local[m / 2 - 1] + local[m / 2])
    };
    Some(SpacingWitness {
        spacing,
        k,
        distinct: distinct.len(),
        h: factor * spacing,
    })
}

/// `ρ_k = √(Σ_{j≤k} δ_j² / k)`, δ_j the distances from a node of the unit square grid to its k
/// nearest other nodes: the squared norms r = 1, 2, 3, … taken in order, each as many times as
/// it has representations r = x² + y² over the integers, until k nodes are counted.
pub fn grid_rms_by_shells(k: usize) -> f64 {
    let mut taken = 0usize;
    let mut sum = 0u64;
    let mut r = 0u64;
    while taken < k {
        r += 1;
        let mut reps = 0usize;
        let mut x = 0u64;
        while x * x <= r {
            let y2 = r - x * x;
            let y = y2.isqrt();
            if y * y == y2 {
                // (±x, ±y): four nodes, two when one coordinate is zero.
                reps += if x == 0 || y == 0 { 2 } else { 4 };
            }
            x += 1;
        }
        let take = reps.min(k - taken);
        taken += take;
        sum += take as u64 * r;
    }
    (sum as f64 / k as f64).sqrt()
}
