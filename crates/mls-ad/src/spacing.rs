//! The spacing's witness (`docs/defaults.md`, `mls_core::normals::spacing_statistics` and
//! `suggest_h`): every distance between distinct positions computed and sorted (mls-core uses
//! a k-d tree on positions centred on their bounding box), the square grid's calibration
//! counted shell by shell (mls-core sorts the nodes of a square), the median of the local
//! spacings, and `h = factor × median`.

use nalgebra::{Matrix3, Point3, Vector3};

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
    // Exact duplicates removed, comparing values (so −0.0 repeats 0.0), first one kept: by the
    // coordinates' bits with −0.0 made 0.0 (`+ 0.0`), which for finite input compares as `==`
    // does, in linear time for the end-to-end row's clouds of 10⁴–10⁵ points.
    let mut seen = std::collections::HashSet::with_capacity(points.len());
    let mut distinct: Vec<Point3<f64>> = Vec::with_capacity(points.len());
    for p in points {
        if seen.insert([p.x, p.y, p.z].map(|c| (c + 0.0).to_bits())) {
            distinct.push(*p);
        }
    }
    if distinct.len() < 2 {
        return None;
    }
    let k = k.min(distinct.len() - 1);
    // Where the k nearest lie along one line (second eigenvalue of their covariance, the point
    // included, below 1e-2 of the largest: `LINE_RATIO`), 4k and then 16k are taken, the first
    // that spans a surface; a point on one line with 16k too (a wire) keeps k.
    let ks = [
        k,
        (4 * k).min(distinct.len() - 1),
        (16 * k).min(distinct.len() - 1),
    ];
    let rho = ks.map(grid_rms_by_shells);
    let order = |a: &(f64, usize), b: &(f64, usize)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
    let mut near: Vec<(f64, usize)> = Vec::with_capacity(distinct.len());
    let mut local: Vec<f64> = distinct
        .iter()
        .enumerate()
        .map(|(i, p)| {
            near.clear();
            near.extend(
                distinct
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(j, q)| ((q - p).norm_squared(), j)),
            );
            // The 16k nearest in order: selected, then sorted (the order is total, so they are
            // those a sort of all would put first).
            if ks[2] < near.len() {
                near.select_nth_unstable_by(ks[2], order);
                near.truncate(ks[2]);
            }
            near.sort_by(order);
            let spacing = |m: usize, rho: f64| {
                (near[..m].iter().map(|n| n.0).sum::<f64>() / m as f64).sqrt() / rho
            };
            let along_one_line = |m: usize| {
                let offsets: Vec<Vector3<f64>> = near[..m]
                    .iter()
                    .map(|&(_, j)| distinct[j] - p)
                    .chain(std::iter::once(Vector3::zeros()))
                    .collect();
                let mean = offsets.iter().sum::<Vector3<f64>>() / offsets.len() as f64;
                let cov = offsets.iter().fold(Matrix3::zeros(), |c, d| {
                    let r = d - mean;
                    c + r * r.transpose()
                });
                let (values, _) = crate::normals::jacobi(cov);
                let mut l = values.map(|v| v.max(0.0));
                l.sort_by(f64::total_cmp);
                l[2] > 0.0 && l[1] < 1e-2 * l[2]
            };
            // The first neighbourhood that spans a surface; a wire keeps k.
            let mut level = 0;
            while level < 2 && ks[level + 1] > ks[level] && along_one_line(ks[level]) {
                level += 1;
                if !along_one_line(ks[level]) {
                    return spacing(ks[level], rho[level]);
                }
            }
            spacing(ks[0], rho[0])
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
