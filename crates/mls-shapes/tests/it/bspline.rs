//! B-spline basis and surface checks.

use approx::assert_relative_eq;
use mls_shapes::{BSplineBasis, BSplineSurface, ParametricSurface, derivatives, position, random};
use num_dual::Dual64;

use crate::seeds;

fn parameters(basis: &BSplineBasis) -> Vec<f64> {
    // Both ends, every knot, and points in between.
    let mut us: Vec<f64> = (0..=200).map(|i| f64::from(i) / 200.0).collect();
    us.extend_from_slice(basis.knots());
    us
}

#[test]
fn partition_of_unity_and_nonnegativity() {
    for (p, n) in [(0, 4), (1, 2), (2, 5), (3, 4), (3, 33), (5, 6), (5, 40)] {
        let basis = BSplineBasis::uniform_clamped(p, n);
        assert_eq!(basis.knots().len(), n + p + 1);
        for u in parameters(&basis) {
            let (first, values) = basis.eval(u);
            assert_eq!(values.len(), p + 1);
            assert!(first + p < n, "degree {p}, {n} functions, u = {u}");
            assert!(
                values.iter().all(|&b| b >= -1e-15),
                "degree {p}, u = {u}: {values:?}"
            );
            assert_relative_eq!(values.iter().sum::<f64>(), 1.0, epsilon = 1e-14);
            // The derivatives of a partition of unity sum to zero.
            let (_, dual) = basis.eval(Dual64::from_re(u).derivative());
            let dsum: f64 = dual.iter().map(|d| d.eps).sum();
            assert!(
                dsum.abs() < 1e-10 * n as f64 * n as f64,
                "degree {p}, u = {u}: {dsum}"
            );
        }
    }
}

#[test]
fn greville_abscissae_give_linear_precision() {
    for (p, n) in [(3, 33), (5, 40), (2, 7)] {
        let basis = BSplineBasis::uniform_clamped(p, n);
        let xi = basis.greville();
        for u in parameters(&basis) {
            let (first, values) = basis.eval(u);
            let x: f64 = values
                .iter()
                .enumerate()
                .map(|(k, b)| b * xi[first + k])
                .sum();
            assert_relative_eq!(x, u.clamp(0.0, 1.0), epsilon = 1e-14);
        }
    }
}

#[test]
fn clamped_net_interpolates_its_corners() {
    for surface in [BSplineSurface::nurbs1(), BSplineSurface::nurbs2()] {
        let [nu, nv] = surface.counts();
        for (u, v, i, j) in [
            (0.0, 0.0, 0, 0),
            (1.0, 0.0, nu - 1, 0),
            (0.0, 1.0, 0, nv - 1),
            (1.0, 1.0, nu - 1, nv - 1),
        ] {
            let corner = surface.control_point(i, j);
            assert!(
                (position(&surface, u, v) - corner).norm() < 1e-12 * (1.0 + corner.coords.norm())
            );
        }
    }
}

#[test]
fn patches_have_the_intended_size() {
    let bbox = |s: &BSplineSurface| {
        let pts: Vec<_> = mls_shapes::grid(s, 101, 101)
            .iter()
            .map(|s| s.surface.point)
            .collect();
        let lo = pts.iter().fold([f64::INFINITY; 3], |a, p| {
            [a[0].min(p.x), a[1].min(p.y), a[2].min(p.z)]
        });
        let hi = pts.iter().fold([f64::NEG_INFINITY; 3], |a, p| {
            [a[0].max(p.x), a[1].max(p.y), a[2].max(p.z)]
        });
        (lo, hi)
    };
    let (lo, hi) = bbox(&BSplineSurface::nurbs1());
    for (got, want) in [(lo[0], 0.0), (hi[0], 1.0), (lo[1], 0.0), (hi[1], 1.0)] {
        assert_relative_eq!(got, want, epsilon = 1e-14);
    }
    assert!(
        hi[2] - lo[2] > 0.1 && hi[2].abs().max(lo[2].abs()) < 0.25,
        "heights {lo:?} {hi:?}"
    );
    let (lo, hi) = bbox(&BSplineSurface::nurbs2());
    assert_relative_eq!(hi[0] - lo[0], 150.0, epsilon = 1e-9);
    assert_relative_eq!(hi[1] - lo[1], 200.0, epsilon = 1e-9);
    assert!(hi[2] > 55.0 && hi[2] < 80.0, "nose tip {}", hi[2]);
}

#[test]
fn dual_derivatives_match_finite_differences() {
    for surface in [BSplineSurface::nurbs1(), BSplineSurface::nurbs2()] {
        let scale = surface
            .control_point(surface.counts()[0] - 1, 0)
            .coords
            .norm()
            .max(1.0);
        let h = 1e-6;
        for s in random(&surface, 50, seeds::PARAMS) {
            let [u, v] = s.uv;
            let d = derivatives(&surface, u, v);
            let fd_u = (position(&surface, u + h, v) - position(&surface, u - h, v)) / (2.0 * h);
            let fd_v = (position(&surface, u, v + h) - position(&surface, u, v - h)) / (2.0 * h);
            assert!(
                (d.du - fd_u).norm() < 1e-6 * scale,
                "{:?}: {} vs {}",
                s.uv,
                d.du,
                fd_u
            );
            assert!((d.dv - fd_v).norm() < 1e-6 * scale, "{:?}", s.uv);
            // Second derivatives: central differences of the exact first derivatives.
            let (up, um) = (
                derivatives(&surface, u + h, v),
                derivatives(&surface, u - h, v),
            );
            let (vp, vm) = (
                derivatives(&surface, u, v + h),
                derivatives(&surface, u, v - h),
            );
            let tol = 1e-4 * scale;
            assert!(
                (d.duu - (up.du - um.du) / (2.0 * h)).norm() < tol,
                "{:?}",
                s.uv
            );
            assert!(
                (d.duv - (vp.du - vm.du) / (2.0 * h)).norm() < tol,
                "{:?}",
                s.uv
            );
            assert!(
                (d.duv - (up.dv - um.dv) / (2.0 * h)).norm() < tol,
                "{:?}",
                s.uv
            );
            assert!(
                (d.dvv - (vp.dv - vm.dv) / (2.0 * h)).norm() < tol,
                "{:?}",
                s.uv
            );
        }
        // The patches are graphs over their rectangle with an affine parametrisation.
        let d = derivatives(&surface, 0.37, 0.61);
        let [nu, nv] = surface.counts();
        let extent = surface.control_point(nu - 1, nv - 1) - surface.control_point(0, 0);
        assert_relative_eq!(d.du.x, extent.x, max_relative = 1e-12);
        assert_relative_eq!(d.dv.y, extent.y, max_relative = 1e-12);
        assert!(d.du.y.abs() < 1e-9 && d.dv.x.abs() < 1e-9);
        assert!(surface.at(0.37, 0.61).normal.z > 0.0);
    }
}
