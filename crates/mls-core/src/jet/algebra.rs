//! The small dense algebra of one jet fit: symmetric matrices as rows, their Cholesky factor,
//! solve and inverse, in forms that vectorise (`#[inline(always)]`, so that each takes on the
//! instruction set of the [`crate::kernels`] copy of the fit it is inlined into).

use super::DETERMINED_PIVOT;

/// A square matrix as rows.
pub(super) type Square<const N: usize> = [[f64; N]; N];

/// Fills `m` with the symmetric matrix of lower-triangle entries `entry(a, b)`, `b ≤ a`.
#[inline(always)]
pub(super) fn symmetric<const N: usize>(m: &mut Square<N>, entry: impl Fn(usize, usize) -> f64) {
    for (a, row) in m.iter_mut().enumerate() {
        for (b, x) in row[..=a].iter_mut().enumerate() {
            *x = entry(a, b);
        }
    }
    mirror(m);
}

/// `tr(A B)` of two symmetric matrices, as their Frobenius product over the lower triangle
/// (N²/2 products, not N³).
#[inline(always)]
pub(super) fn trace_product<const N: usize>(a: &Square<N>, b: &Square<N>) -> f64 {
    let mut diagonal = 0.0;
    let mut off = 0.0;
    for i in 0..N {
        diagonal += a[i][i] * b[i][i];
        off += dot_prefix(&a[i], &b[i], i);
    }
    diagonal + 2.0 * off
}

/// A Cholesky factor `L` (`LLᵀ = A`) with the reciprocals of its diagonal, formed in place
/// ([`Factor::factor`]).
pub(super) struct Factor<const N: usize> {
    /// `L` in the lower triangle and on the diagonal (the strict upper triangle is not read).
    pub(super) l: Square<N>,
    pub(super) inv_diag: [f64; N],
}

/// Copies the strict lower triangle of `m` onto the upper.
#[inline(always)]
pub(super) fn mirror<const N: usize>(m: &mut Square<N>) {
    for i in 1..N {
        let (above, below) = m.split_at_mut(i);
        for (j, row) in above.iter_mut().enumerate() {
            row[i] = below[0][j];
        }
    }
}

/// `Σ_{k<n} x_k y_k`.
#[inline(always)]
pub(super) fn dot_prefix(x: &[f64], y: &[f64], n: usize) -> f64 {
    x[..n].iter().zip(&y[..n]).map(|(x, y)| x * y).sum()
}

impl<const N: usize> Factor<N> {
    /// Replaces the symmetric matrix `A` held in `l` by its lower Cholesky factor; false when
    /// the samples do not determine the basis, and fitting it would fit noise or truncation:
    /// a squared pivot below `1e-10` of the largest diagonal entry (too few samples, or on a
    /// line), or below [`DETERMINED_PIVOT`] of its own diagonal entry (samples on a few lines:
    /// a basis function nearly in the span of those before it).
    ///
    /// Right-looking (each column, then a rank-1 update of the rest): the updates are
    /// independent along a row, so they run as vector operations rather than one chain of
    /// dependent sums.
    #[inline(always)]
    pub(super) fn factor(&mut self) -> bool {
        let (l, inv_diag) = (&mut self.l, &mut self.inv_diag);
        let max_diag = (0..N).map(|i| l[i][i]).fold(0.0f64, f64::max);
        // Each pivot's floor, from the diagonal before the updates.
        let mut floor = [0.0; N];
        for (k, f) in floor.iter_mut().enumerate() {
            *f = (1e-10 * max_diag).max(DETERMINED_PIVOT * l[k][k]);
        }
        for k in 0..N {
            let s = l[k][k];
            if !(s > floor[k]) {
                return false;
            }
            l[k][k] = s.sqrt();
            inv_diag[k] = 1.0 / l[k][k];
            let mut column = [0.0; N];
            for i in k + 1..N {
                column[i] = l[i][k] * inv_diag[k];
                l[i][k] = column[i];
            }
            for i in k + 1..N {
                let f = column[i];
                for (r, c) in l[i][k + 1..=i].iter_mut().zip(&column[k + 1..=i]) {
                    *r -= f * c;
                }
            }
        }
        true
    }

    /// `x` with `LLᵀ x = b`, by forward and back substitution.
    #[inline(always)]
    pub(super) fn solve(&self, b: &[f64; N]) -> [f64; N] {
        let (l, d) = (&self.l, &self.inv_diag);
        let mut y = [0.0; N];
        for i in 0..N {
            y[i] = (b[i] - dot_prefix(&l[i], &y, i)) * d[i];
        }
        let mut x = [0.0; N];
        for i in (0..N).rev() {
            let s: f64 = (i + 1..N).map(|k| l[k][i] * x[k]).sum();
            x[i] = (y[i] - s) * d[i];
        }
        x
    }

    /// `A⁻¹ = L⁻ᵀ L⁻¹`, from the rows of `L⁻¹` (each a combination of the rows above it) and
    /// their outer products: both as independent updates along a row, which vectorise.
    #[inline(always)]
    pub(super) fn inverse(&self, inv: &mut Square<N>) {
        let (l, d) = (&self.l, &self.inv_diag);
        // Row k of L⁻¹ is d_k (e_k − Σ_{m<k} l_km row_m); it vanishes past column k.
        let mut li = [[0.0; N]; N];
        for k in 0..N {
            let mut row = [0.0; N];
            row[k] = 1.0;
            for (m, &f) in l[k][..k].iter().enumerate() {
                for (r, x) in row[..=m].iter_mut().zip(&li[m][..=m]) {
                    *r -= f * x;
                }
            }
            for (x, r) in li[k][..=k].iter_mut().zip(&row[..=k]) {
                *x = r * d[k];
            }
        }
        // (L⁻ᵀ L⁻¹)_ij = Σ_k li_ki li_kj, summed over the rows.
        *inv = [[0.0; N]; N];
        for (k, row) in li.iter().enumerate() {
            for (i, &f) in row[..=k].iter().enumerate() {
                for (x, r) in inv[i][..=i].iter_mut().zip(&row[..=i]) {
                    *x += f * r;
                }
            }
        }
        mirror(inv);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A squared pivot at exactly `1e-10` of the largest diagonal entry leaves the basis
    /// undetermined; twice that is factored.
    #[test]
    fn a_pivot_at_the_threshold_is_refused() {
        let at = |pivot: f64| {
            let mut f = Factor::<2> {
                l: [[1.0, 0.0], [0.0, pivot]],
                inv_diag: [0.0; 2],
            };
            f.factor()
        };
        assert!(!at(1e-10));
        assert!(at(2e-10));
    }

    /// A basis function whose part outside the span of the one before it is a fraction `δ` of
    /// its norm has the squared pivot `δ²` of its diagonal entry: refused at half of
    /// `DETERMINED_PIVOT`, factored at twice it, whatever its scale against the first.
    #[test]
    fn a_basis_function_nearly_in_the_span_of_the_others_is_refused() {
        let at = |delta2: f64, scale: f64| {
            // Unit vectors at angle θ, sin²θ = δ², the second scaled by `scale`.
            let c = (1.0 - delta2).sqrt() * scale;
            let mut f = Factor::<2> {
                l: [[1.0, c], [c, scale * scale]],
                inv_diag: [0.0; 2],
            };
            f.factor()
        };
        for scale in [1.0, 1e-2] {
            assert!(!at(0.5 * DETERMINED_PIVOT, scale), "scale {scale}");
            assert!(at(2.0 * DETERMINED_PIVOT, scale), "scale {scale}");
        }
    }
}
