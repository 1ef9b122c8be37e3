//! Normal estimation's witness (Sec. 4.1 with the centroid normalised, erratum E2 of
//! `docs/derivation.md`): the k nearest neighbours by sorting every distance, the weighted
//! covariance from its definition, and a cyclic Jacobi eigen-solve written here (mls-core uses
//! a kd-tree and nalgebra's `SymmetricEigen`).

use nalgebra::{Matrix3, Point3, Vector3};

/// The witness's normal at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NormalWitness {
    /// Unit eigenvector of the smallest eigenvalue (sign arbitrary).
    pub normal: Vector3<f64>,
    /// Eigenvalues `λ0 ≤ λ1 ≤ λ2` of the covariance (divided by Σθ).
    pub eigenvalues: [f64; 3],
    /// `λ0 / (λ0 + λ1 + λ2)`.
    pub variation: f64,
}

/// The normal of `points[index]` from itself and its `k` nearest other points (all others
/// when there are at most `k`), weights `θ = exp(−|q − p|²/h²)`; `None` when the
/// neighbourhood is degenerate (fewer than 3 points, `λ1 − λ0 ≤ tolerance · λ2`, or
/// `λ1 < 1e-2 λ2`: along one line, `LINE_RATIO`) with `4k` and with `16k` neighbours too, where
/// h is widened to half the distance of the farthest neighbour if that is larger.
pub fn normal_witness(
    index: usize,
    points: &[Point3<f64>],
    k: usize,
    h: f64,
    tolerance: f64,
) -> Option<NormalWitness> {
    let p = points[index];
    let mut others: Vec<(f64, usize)> = points
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != index)
        .map(|(j, q)| ((q - p).norm_squared(), j))
        .collect();
    others.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    for times in [1, 4, 16] {
        let m = (k * times).min(others.len());
        let offsets: Vec<Vector3<f64>> = std::iter::once(Vector3::zeros())
            .chain(others[..m].iter().map(|&(_, j)| points[j] - p))
            .collect();
        let scale = if times == 1 {
            h
        } else {
            h.max(others[..m].last().map_or(0.0, |o| o.0.sqrt()) / 2.0)
        };
        if let Some(w) = covariance_normal(&offsets, scale, tolerance) {
            return Some(w);
        }
        if m == others.len() && times > 1 {
            break;
        }
    }
    None
}

/// The weighted covariance normal of `offsets` (the point itself first, at zero).
fn covariance_normal(offsets: &[Vector3<f64>], h: f64, tolerance: f64) -> Option<NormalWitness> {
    if offsets.len() < 3 {
        return None;
    }
    let inv_h2 = 1.0 / (h * h);
    let weights: Vec<f64> = offsets
        .iter()
        .map(|d| (-d.norm_squared() * inv_h2).exp())
        .collect();
    let sum: f64 = weights.iter().sum();
    let centroid = offsets
        .iter()
        .zip(&weights)
        .fold(Vector3::zeros(), |c, (d, w)| c + d * *w)
        / sum;
    let cov = offsets
        .iter()
        .zip(&weights)
        .fold(Matrix3::zeros(), |c, (d, w)| {
            let r = d - centroid;
            c + r * r.transpose() * *w
        })
        / sum;
    let (values, vectors) = jacobi(cov);
    let mut order = [0, 1, 2];
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let eigenvalues = order.map(|i| values[i].max(0.0));
    let [l0, l1, l2] = eigenvalues;
    if !(l2 > 0.0 && l1 - l0 > tolerance * l2 && l1 >= 1e-2 * l2) {
        return None;
    }
    Some(NormalWitness {
        normal: vectors.column(order[0]).normalize(),
        eigenvalues,
        variation: l0 / (l0 + l1 + l2),
    })
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3 × 3 matrix by cyclic Jacobi
/// rotations (Golub & Van Loan, Alg. 8.5.3): each rotation zeroes one off-diagonal entry;
/// sweeps repeat until the off-diagonal part is zero or below rounding.
pub fn jacobi(mut a: Matrix3<f64>) -> ([f64; 3], Matrix3<f64>) {
    let mut v = Matrix3::identity();
    for _ in 0..50 {
        let off = a[(0, 1)].powi(2) + a[(0, 2)].powi(2) + a[(1, 2)].powi(2);
        let diag = a[(0, 0)].powi(2) + a[(1, 1)].powi(2) + a[(2, 2)].powi(2);
        if !(off > (f64::EPSILON * f64::EPSILON * 1e-4) * diag) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[(p, q)] == 0.0 {
                continue;
            }
            let theta = (a[(q, q)] - a[(p, p)]) / (2.0 * a[(p, q)]);
            let t = 1.0_f64.copysign(theta) / (theta.abs() + theta.hypot(1.0));
            let c = 1.0 / t.hypot(1.0);
            let s = t * c;
            let mut j = Matrix3::identity();
            j[(p, p)] = c;
            j[(q, q)] = c;
            j[(p, q)] = s;
            j[(q, p)] = -s;
            a = j.transpose() * a * j;
            a[(p, q)] = 0.0;
            a[(q, p)] = 0.0;
            v *= j;
        }
    }
    ([a[(0, 0)], a[(1, 1)], a[(2, 2)]], v)
}
