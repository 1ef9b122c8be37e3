//! Curvature values against closed forms, and the automatic-differentiation path against the
//! closed-form overrides.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use approx::assert_relative_eq;
use mls_shapes::{
    Cylinder, Ellipsoid, HeightField, HeightFieldConfig, Orientation, ParamInterval,
    ParametricSurface, Point, Saddle, Scalar, Sphere, SurfacePoint, Torus, Vector, derivatives,
    differential_geometry, grid, random,
};
use nalgebra::{SVector, Vector2};
use num_dual::{Dual2SVec64, hessian};

use crate::{alignment, seeds};

#[test]
fn sphere_has_inverse_radius_curvature_with_outward_normals() {
    let sphere = Sphere::new(Point::new(1.0, -2.0, 0.5), 2.5);
    for s in grid(&sphere, 9, 16) {
        for (what, p) in [
            ("closed", s.surface),
            ("ad", differential_geometry(&sphere, s.uv[0], s.uv[1])),
        ] {
            let radial = (p.point - sphere.center) / sphere.radius;
            assert_relative_eq!(radial.norm(), 1.0, epsilon = 1e-14);
            assert!((p.normal - radial).norm() < 1e-12, "{what} {:?}", s.uv);
            assert_relative_eq!(p.k1, 0.4, epsilon = 1e-12);
            assert_relative_eq!(p.k2, 0.4, epsilon = 1e-12);
            assert_relative_eq!(p.mean(), 0.4, epsilon = 1e-12);
            assert_relative_eq!(p.gauss(), 0.16, epsilon = 1e-12);
        }
    }
}

#[test]
fn sphere_closed_form_is_valid_at_the_poles() {
    let sphere = Sphere::centered(2.0);
    for (theta, z) in [(0.0, 1.0), (PI, -1.0)] {
        let p = sphere.at(theta, 0.7);
        crate::assert_frame(&p, 1e-14, "pole");
        assert!((p.normal - Vector::new(0.0, 0.0, z)).norm() < 1e-15);
    }
}

#[test]
fn cylinder_has_inverse_radius_and_zero() {
    let cylinder = Cylinder::new(0.75, 3.0);
    for s in grid(&cylinder, 12, 5) {
        for p in [
            s.surface,
            differential_geometry(&cylinder, s.uv[0], s.uv[1]),
        ] {
            let radial = Vector::new(p.point.x, p.point.y, 0.0) / cylinder.radius;
            assert!((p.normal - radial).norm() < 1e-12);
            assert_relative_eq!(p.k1, 1.0 / 0.75, epsilon = 1e-12);
            assert!(p.k2.abs() < 1e-12);
            assert_relative_eq!(alignment(&p.d2, &Vector::z()), 1.0, epsilon = 1e-12);
        }
    }
}

#[test]
fn torus_matches_closed_form_at_several_tube_angles() {
    let (big_r, r) = (2.0, 0.6);
    let torus = Torus::new(big_r, r);
    for phi in [0.0, 0.4, FRAC_PI_2, 2.0, PI, 4.0, 3.0 * FRAC_PI_2, 5.9] {
        // Formulas written here from the geometry, independently of the crate's closed form.
        let (k_tube, k_parallel) = (1.0 / r, phi.cos() / (big_r + r * phi.cos()));
        for theta in [0.0, 1.1, 4.2] {
            let ad = differential_geometry(&torus, theta, phi);
            assert_relative_eq!(ad.k1, k_tube, epsilon = 1e-12);
            assert_relative_eq!(ad.k2, k_parallel, epsilon = 1e-12);
            // The tube direction lies in the meridian plane: no azimuthal component.
            let azimuthal = Vector::new(-theta.sin(), theta.cos(), 0.0);
            assert!(alignment(&ad.d1, &azimuthal) < 1e-12);
            assert_relative_eq!(alignment(&ad.d2, &azimuthal), 1.0, epsilon = 1e-12);
        }
    }
    // Outer equator: elliptic, both positive; inner equator: hyperbolic.
    let outer = torus.at(0.3, 0.0);
    assert!(outer.k1 > 0.0 && outer.k2 > 0.0 && outer.gauss() > 0.0);
    let inner = torus.at(0.3, PI);
    assert!(inner.k1 > 0.0 && inner.k2 < 0.0 && inner.gauss() < 0.0);
    assert_relative_eq!(inner.k2, -1.0 / (big_r - r), epsilon = 1e-12);
}

#[test]
fn automatic_differentiation_matches_closed_forms() {
    fn compare<S: ParametricSurface>(name: &str, surface: &S, umbilic: bool) {
        for s in random(surface, 200, seeds::PARAMS) {
            let [u, v] = s.uv;
            let (closed, ad) = (s.surface, differential_geometry(surface, u, v));
            let ctx = format!("{name} at {:?}", s.uv);
            assert!((closed.point - ad.point).norm() < 1e-12, "{ctx}");
            assert!((closed.normal - ad.normal).norm() < 1e-12, "{ctx}");
            assert!(
                (closed.k1 - ad.k1).abs() < 1e-12,
                "{ctx}: {} vs {}",
                closed.k1,
                ad.k1
            );
            assert!(
                (closed.k2 - ad.k2).abs() < 1e-12,
                "{ctx}: {} vs {}",
                closed.k2,
                ad.k2
            );
            assert!(
                (closed.shape_tensor() - ad.shape_tensor()).norm() < 1e-12,
                "{ctx}"
            );
            if !umbilic {
                assert!((alignment(&closed.d1, &ad.d1) - 1.0).abs() < 1e-12, "{ctx}");
                assert!((alignment(&closed.d2, &ad.d2) - 1.0).abs() < 1e-12, "{ctx}");
            }
        }
    }
    compare(
        "sphere",
        &Sphere::new(Point::new(0.3, 0.1, -0.2), 1.7),
        true,
    );
    compare("cylinder", &Cylinder::new(0.4, 2.0), false);
    compare("torus", &Torus::new(1.0, 0.35), false);
}

#[test]
fn ellipsoid_axis_ends() {
    let (a, b, c) = (3.0, 2.0, 1.0);
    let e = Ellipsoid::new(a, b, c);
    // End of the a-axis: a/b² towards y, a/c² towards z.
    let p = e.at(FRAC_PI_2, 0.0);
    assert!((p.point - Point::new(a, 0.0, 0.0)).norm() < 1e-15);
    assert!((p.normal - Vector::x()).norm() < 1e-15);
    assert_relative_eq!(p.k1, a / (c * c), epsilon = 1e-12);
    assert_relative_eq!(p.k2, a / (b * b), epsilon = 1e-12);
    assert_relative_eq!(alignment(&p.d1, &Vector::z()), 1.0, epsilon = 1e-12);
    assert_relative_eq!(alignment(&p.d2, &Vector::y()), 1.0, epsilon = 1e-12);
    // End of the b-axis: b/c² towards z, b/a² towards x.
    let p = e.at(FRAC_PI_2, FRAC_PI_2);
    assert_relative_eq!(p.k1, b / (c * c), epsilon = 1e-12);
    assert_relative_eq!(p.k2, b / (a * a), epsilon = 1e-12);
    // The c-axis ends are the parametrisation's poles; approach one.
    let p = e.at(1e-6, 0.3);
    assert_relative_eq!(p.k1, c / (b * b), epsilon = 1e-9);
    assert_relative_eq!(p.k2, c / (a * a), epsilon = 1e-9);
}

#[test]
fn ellipsoid_matches_closed_form_gauss_and_mean() {
    let e = Ellipsoid::new(1.3, 0.8, 2.1);
    for s in random(&e, 300, seeds::PARAMS) {
        let p = s.surface;
        assert_relative_eq!(p.gauss(), e.gauss_at(&p.point), max_relative = 1e-11);
        assert_relative_eq!(p.mean(), e.mean_at(&p.point), max_relative = 1e-11);
    }
}

#[test]
fn saddle_at_origin() {
    let a = 0.8;
    let saddle = Saddle::new(a, 1.0);
    let p = saddle.at(0.0, 0.0);
    assert!((p.normal - Vector::z()).norm() < 1e-15);
    assert_relative_eq!(p.k1, 1.0 / a, epsilon = 1e-14);
    assert_relative_eq!(p.k2, -1.0 / a, epsilon = 1e-14);
    assert_relative_eq!(alignment(&p.d1, &Vector::y()), 1.0, epsilon = 1e-14);
    assert_relative_eq!(alignment(&p.d2, &Vector::x()), 1.0, epsilon = 1e-14);
    // Away from the origin the normal stays on the +z side.
    assert!(grid(&saddle, 7, 7).iter().all(|s| s.surface.normal.z > 0.0));
}

/// Differential test of the fundamental-form code: for a graph `z = f(x, y)` with normal on
/// the +z side the Monge-patch formulas give, in this crate's sign convention,
/// `K = (f_xx f_yy − f_xy²) / (1 + |∇f|²)²` and
/// `H = −((1 + f_y²) f_xx − 2 f_x f_y f_xy + (1 + f_x²) f_yy) / (2 (1 + |∇f|²)^{3/2})`,
/// with the derivatives of f taken by num-dual directly from the height.
fn check_monge<F>(height: F, samples: &[mls_shapes::Sample], name: &str)
where
    F: Fn(Dual2SVec64<2>, Dual2SVec64<2>) -> Dual2SVec64<2>,
{
    for s in samples {
        let (_, g, h) = hessian(
            |p: SVector<Dual2SVec64<2>, 2>| height(p[0], p[1]),
            &Vector2::from(s.uv),
        );
        let w = 1.0 + g.norm_squared();
        let gauss = (h[(0, 0)] * h[(1, 1)] - h[(0, 1)] * h[(0, 1)]) / (w * w);
        let mean = -((1.0 + g[1] * g[1]) * h[(0, 0)] - 2.0 * g[0] * g[1] * h[(0, 1)]
            + (1.0 + g[0] * g[0]) * h[(1, 1)])
            / (2.0 * w.powf(1.5));
        let p = s.surface;
        assert!(
            (p.gauss() - gauss).abs() < 1e-12 * (1.0 + gauss.abs()),
            "{name} {:?}",
            s.uv
        );
        assert!(
            (p.mean() - mean).abs() < 1e-12 * (1.0 + mean.abs()),
            "{name} {:?}",
            s.uv
        );
        let up = Vector::new(-g[0], -g[1], 1.0) / w.sqrt();
        assert!((p.normal - up).norm() < 1e-12, "{name} {:?}", s.uv);
    }
}

#[test]
fn height_fields_match_monge_formulas() {
    let saddle = Saddle::new(0.6, 1.5);
    check_monge(
        |x, y| saddle.height(x, y),
        &random(&saddle, 100, seeds::PARAMS),
        "saddle",
    );
    for k in 0..5 {
        let field = HeightField::random(&HeightFieldConfig::default(), seeds::HEIGHT_FIELD + k);
        let samples = random(&field, 100, seeds::PARAMS);
        check_monge(
            |x, y| field.height(x, y),
            &samples,
            &format!("height field seed {}", seeds::HEIGHT_FIELD + k),
        );
    }
}

/// The sign convention checked from the normal field alone: central differences of the unit
/// normal along `r_u` and `r_v` must equal the shape tensor `W = dN` applied to them.
fn check_normal_derivative<S: ParametricSurface>(name: &str, surface: &S, h: f64) {
    for s in random(surface, 60, seeds::PARAMS) {
        let [u, v] = s.uv;
        let d = derivatives(surface, u, v);
        let w = s.surface.shape_tensor();
        let dn_du = (surface.at(u + h, v).normal - surface.at(u - h, v).normal) / (2.0 * h);
        let dn_dv = (surface.at(u, v + h).normal - surface.at(u, v - h).normal) / (2.0 * h);
        let scale = 1.0 + w.norm() * d.du.norm().max(d.dv.norm());
        assert!(
            (dn_du - w * d.du).norm() < 1e-6 * scale,
            "{name} at {:?}: {dn_du} vs {}",
            s.uv,
            w * d.du
        );
        assert!(
            (dn_dv - w * d.dv).norm() < 1e-6 * scale,
            "{name} at {:?}",
            s.uv
        );
    }
}

#[test]
fn shape_tensor_is_the_derivative_of_the_normal() {
    check_normal_derivative("sphere", &Sphere::centered(1.3), 1e-5);
    check_normal_derivative("cylinder", &Cylinder::new(0.5, 1.0), 1e-5);
    check_normal_derivative("torus", &Torus::new(1.0, 0.3), 1e-5);
    check_normal_derivative("ellipsoid", &Ellipsoid::new(1.0, 2.0, 0.5), 1e-5);
    check_normal_derivative("saddle", &Saddle::new(0.7, 1.0), 1e-5);
    let field = HeightField::random(&HeightFieldConfig::default(), seeds::HEIGHT_FIELD);
    check_normal_derivative("height field", &field, 1e-5);
    check_normal_derivative("nurbs1", &mls_shapes::BSplineSurface::nurbs1(), 1e-6);
    check_normal_derivative("nurbs2", &mls_shapes::BSplineSurface::nurbs2(), 1e-6);
}

/// The sphere parametrised with `(u, v) = (φ, θ)`: swapping the parameters flips
/// `r_u × r_v` inward, which [`Orientation::Reversed`] must undo.
struct SwappedSphere(Sphere);

impl ParametricSurface for SwappedSphere {
    fn domain(&self) -> [ParamInterval; 2] {
        let [theta, phi] = self.0.domain();
        [phi, theta]
    }
    fn position<D: Scalar>(&self, u: D, v: D) -> [D; 3] {
        self.0.position(v, u)
    }
    fn orientation(&self) -> Orientation {
        Orientation::Reversed
    }
}

#[test]
fn reversed_orientation_flips_the_normal_and_the_curvatures_back() {
    let sphere = Sphere::centered(0.9);
    let swapped = SwappedSphere(sphere);
    for s in random(&swapped, 50, seeds::PARAMS) {
        let p = s.surface;
        let truth: SurfacePoint = sphere.at(s.uv[1], s.uv[0]);
        assert!((p.normal - truth.normal).norm() < 1e-12);
        assert_relative_eq!(p.k1, 1.0 / 0.9, epsilon = 1e-12);
        assert_relative_eq!(p.k2, 1.0 / 0.9, epsilon = 1e-12);
        crate::assert_frame(&p, 1e-12, "swapped sphere");
    }
}

/// Gauss–Bonnet as a global check of K and of the area element: `∫ K dA = 2π χ`.
fn total_curvature<S: ParametricSurface>(surface: &S, nu: usize, nv: usize) -> f64 {
    let [du, dv] = surface.domain();
    let cell = du.len() / nu as f64 * dv.len() / nv as f64;
    grid(surface, nu, nv)
        .iter()
        .map(|s| s.surface.gauss() * derivatives(surface, s.uv[0], s.uv[1]).area_element() * cell)
        .sum()
}

#[test]
fn gauss_bonnet() {
    // Periodic in both parameters: the rectangle rule is spectrally accurate, χ = 0.
    assert!(total_curvature(&Torus::new(1.5, 0.5), 64, 64).abs() < 1e-10);
    // Midpoint rule in θ: second order, χ = 2.
    let sphere = total_curvature(&Sphere::centered(0.7), 200, 64);
    assert_relative_eq!(sphere, 2.0 * TAU, max_relative = 1e-4);
    let ellipsoid = total_curvature(&Ellipsoid::new(1.0, 1.5, 0.6), 200, 64);
    assert_relative_eq!(ellipsoid, 2.0 * TAU, max_relative = 1e-3);
}
