//! Principal directions are unit, orthogonal, tangent and right-handed on every shape.

use mls_shapes::{
    BSplineSurface, Cylinder, Ellipsoid, HeightField, HeightFieldConfig, ParametricSurface, Point,
    Saddle, Sphere, Torus, differential_geometry, random,
};

use crate::{assert_frame, seeds};

fn check<S: ParametricSurface>(name: &str, surface: &S) {
    for s in random(surface, 100, seeds::PARAMS) {
        let ctx = format!("{name} at {:?} (seed {:#x})", s.uv, seeds::PARAMS);
        assert_frame(&s.surface, 1e-12, &ctx);
        assert_frame(
            &differential_geometry(surface, s.uv[0], s.uv[1]),
            1e-12,
            &ctx,
        );
    }
}

#[test]
fn frames_on_every_shape() {
    check("sphere", &Sphere::new(Point::new(1.0, 2.0, 3.0), 0.5));
    check("cylinder", &Cylinder::new(2.0, 1.0));
    check("torus", &Torus::new(3.0, 1.0));
    check("ellipsoid", &Ellipsoid::new(0.5, 1.0, 2.0));
    check("saddle", &Saddle::new(1.0, 2.0));
    check(
        "height field",
        &HeightField::random(&HeightFieldConfig::default(), seeds::HEIGHT_FIELD),
    );
    check("nurbs1", &BSplineSurface::nurbs1());
    check("nurbs2", &BSplineSurface::nurbs2());
}
