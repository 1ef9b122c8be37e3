//! The orientation rows of `cargo xtask validate`: normals estimated and oriented through the
//! command's own library entry (`mls_pipeline::pipeline`: the index, h from the spacing with the
//! default factor, `normals` with `--normals estimate` and the command's `--orient`) on noisy,
//! irregular samples of closed analytic shapes and of height fields, without their normals,
//! checked against the shapes' geometry, and the summary's share of neighbour pairs that agree
//! against `mls_ad::pair_agreement`.

use std::fmt::Write as _;

use anyhow::Result;
use mls_core::normals::{DEFAULT_H_FACTOR, Orientation};
use mls_core::{Frame, Parallelism, Point, Vector};
use mls_pipeline::NormalsMode;
use mls_shapes::{Ellipsoid, HeightField, HeightFieldConfig, Sphere, Torus, random_area_uniform};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::validate::{Q, Tally};

/// The shapes, in turn.
#[derive(Clone, Copy, Debug)]
enum Shape {
    Sphere,
    Ellipsoid,
    Torus,
    /// A box: flat faces meeting at 90° creases.
    Cuboid,
    /// A height field with the command's default orientation (up, for a sheet seen from
    /// above).
    SheetDefault,
    /// A height field with `--orient viewpoint:X,Y,Z`, the viewpoint high above it.
    SheetViewpoint,
}

const SHAPES: [Shape; 6] = [
    Shape::Sphere,
    Shape::Ellipsoid,
    Shape::Torus,
    Shape::Cuboid,
    Shape::SheetDefault,
    Shape::SheetViewpoint,
];

/// The torus's major radius (its core circle's, about the z axis through its centre).
const TORUS_MAJOR: f64 = 1.0;

/// One cloud: its points, per point the direction its oriented normal must face (outward, or
/// the sheet's upper side), and the `--orient` the command gets.
struct Cloud {
    name: String,
    points: Vec<Point>,
    truth: Vec<Vector>,
    orient: Option<Orientation>,
}

/// Random area-uniform samples (irregular: no lattice), Gaussian position noise of up to 0.3
/// of the mean spacing; the truth direction from the shape's implicit function at the
/// noisy point: `∇f` for the sphere and ellipsoid (`n·(x − c) > 0` is outward), `x − c(x)` for
/// the torus with `c(x)` the nearest point of the tube's core circle; for the height fields the
/// upward normal at the sample.
fn cloud(shape: Shape, rng: &mut ChaCha8Rng) -> Cloud {
    let n = rng.random_range(2_000..4_000);
    let seed = rng.random();
    let centre = Vector::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    if let Shape::Cuboid = shape {
        return cuboid(n, centre, rng);
    }
    // The ellipsoid's semi-axes (the sphere's gradient is the same with axes 1).
    let mut axes = Vector::new(1.0, 1.0, 1.0);
    let (name, samples, area): (String, Vec<mls_shapes::Sample>, f64) = match shape {
        Shape::Sphere => {
            let r = rng.random_range(0.5..2.0);
            let s = Sphere::centered(r);
            (
                format!("sphere R = {r:.2}"),
                random_area_uniform(&s, n, seed),
                4.0 * std::f64::consts::PI * r * r,
            )
        }
        Shape::Ellipsoid => {
            let (a, b, c) = (
                rng.random_range(0.6..1.4),
                rng.random_range(0.6..1.4),
                rng.random_range(0.5..1.0),
            );
            axes = Vector::new(a, b, c);
            let s = Ellipsoid::new(a, b, c);
            // Knud Thomsen's approximation of the area (within 1.1 %): only for the spacing.
            let p = 1.6075;
            let area = 4.0
                * std::f64::consts::PI
                * (((a * b).powf(p) + (a * c).powf(p) + (b * c).powf(p)) / 3.0).powf(1.0 / p);
            (
                format!("ellipsoid {a:.2} × {b:.2} × {c:.2}"),
                random_area_uniform(&s, n, seed),
                area,
            )
        }
        Shape::Torus => {
            // Twice the points: the tube's radius 5–11 spacings.
            let minor = rng.random_range(0.3..0.5);
            let s = Torus {
                major: TORUS_MAJOR,
                minor,
            };
            (
                format!("torus R = 1, r = {minor:.2}"),
                random_area_uniform(&s, 2 * n, seed),
                4.0 * std::f64::consts::PI.powi(2) * TORUS_MAJOR * minor,
            )
        }
        Shape::Cuboid => unreachable!("sampled by `cuboid`"),
        Shape::SheetDefault | Shape::SheetViewpoint => {
            let config = HeightFieldConfig {
                amplitude: rng.random_range(0.05..0.2),
                ..HeightFieldConfig::default()
            };
            let s = HeightField::random(&config, rng.random());
            let w = config.half_width;
            (
                "height field".to_string(),
                random_area_uniform(&s, n, seed),
                4.0 * w * w,
            )
        }
    };
    let spacing = (area / samples.len() as f64).sqrt();
    let exact: Vec<[f64; 3]> = samples
        .iter()
        .map(|s| (s.surface.point + centre).coords.into())
        .collect();
    let sigma = rng.random_range(0.0..0.3) * spacing;
    let noisy = mls_shapes::add_position_noise(&exact, sigma, rng.random());
    let points: Vec<Point> = noisy.iter().map(|p| Point::from(*p)).collect();
    let truth: Vec<Vector> = points
        .iter()
        .zip(&samples)
        .map(|(x, s)| {
            let d = x.coords - centre;
            match shape {
                Shape::Sphere | Shape::Ellipsoid => d.component_div(&axes.component_mul(&axes)),
                Shape::Cuboid => unreachable!("sampled by `cuboid`"),
                Shape::Torus => {
                    let radial = Vector::new(d.x, d.y, 0.0);
                    d - radial.normalize() * TORUS_MAJOR
                }
                Shape::SheetDefault | Shape::SheetViewpoint => {
                    let n = s.surface.normal;
                    if n.z < 0.0 { -n } else { n }
                }
            }
        })
        .collect();
    let orient = match shape {
        Shape::SheetViewpoint => {
            let v = Point::from(centre + Vector::new(0.0, 0.0, rng.random_range(5.0..50.0)));
            Some(Orientation::Viewpoint(v))
        }
        _ => None,
    };
    Cloud {
        name: format!(
            "{name}, {} points, noise {:.2} spacing",
            points.len(),
            sigma / spacing
        ),
        points,
        truth,
        orient,
    }
}

/// `n` random points on the faces of a box of half-sides 0.5–1.5 (each face in proportion to
/// its area), Gaussian noise of up to a tenth of the spacing; the truth direction is the
/// outward normal of the face each point was drawn on, away from the face's edges.
fn cuboid(n: usize, centre: Vector, rng: &mut ChaCha8Rng) -> Cloud {
    let half = Vector::new(
        rng.random_range(0.5..1.5),
        rng.random_range(0.5..1.5),
        rng.random_range(0.5..1.5),
    );
    // Faces by axis: the area of each pair, 2 · (2a · 2b).
    let areas = [
        4.0 * half.y * half.z,
        4.0 * half.x * half.z,
        4.0 * half.x * half.y,
    ];
    let total = 2.0 * areas.iter().sum::<f64>();
    let spacing = (total / n as f64).sqrt();
    let sigma = rng.random_range(0.0..0.1) * spacing;
    let (mut points, mut truth) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for _ in 0..n {
        let mut pick = rng.random_range(0.0..total / 2.0);
        let mut axis = 0;
        while axis < 2 && pick >= areas[axis] {
            pick -= areas[axis];
            axis += 1;
        }
        let side = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let mut p = Vector::new(
            rng.random_range(-half.x..half.x),
            rng.random_range(-half.y..half.y),
            rng.random_range(-half.z..half.z),
        );
        p[axis] = side * half[axis];
        // The face's normal, where the face's geometry decides the sign: farther than three
        // spacings (beyond the 16 neighbours' reach, about 2.3) from its edges. Nearer, the
        // estimated normal blends the faces and a crease decides nothing (`docs/orientation.md`
        // leaves pairs across creases out for the same reason): no truth (zero).
        let mut normal = Vector::zeros();
        let inside = (0..3)
            .filter(|&b| b != axis)
            .all(|b| half[b] - p[b].abs() > 3.0 * spacing);
        if inside {
            normal[axis] = side;
        }
        let noise = Vector::new(
            rng.sample::<f64, _>(rand_distr::StandardNormal),
            rng.sample::<f64, _>(rand_distr::StandardNormal),
            rng.sample::<f64, _>(rand_distr::StandardNormal),
        );
        points.push(Point::from(centre + p + noise * sigma));
        truth.push(normal);
    }
    Cloud {
        name: format!(
            "box {:.2} × {:.2} × {:.2}, {n} points, noise {:.2} spacing",
            2.0 * half.x,
            2.0 * half.y,
            2.0 * half.z,
            sigma / spacing
        ),
        points,
        truth,
        orient: None,
    }
}

/// The summary's "P% of neighbour pairs agree", as printed.
pub(crate) fn printed_agreement(source: &str) -> Option<&str> {
    let end = source.find("% of neighbour pairs agree")?;
    let start = source[..end].rfind(' ')? + 1;
    Some(&source[start..end])
}

/// One cloud per case, the shapes in turn: records the two side rows (share of the normals
/// whose sign their geometry decides that face the wrong way) and the printed agreement row
/// (1 where the summary's share differs from the recount as printed), and returns the
/// report's table.
pub(crate) fn check_orientation(tally: &mut Tally, base_seed: u64, cases: usize) -> Result<String> {
    let mut table = String::from(
        "\nOrientation (estimated normals through `mls_pipeline::pipeline::normals`, as `mlscurv \
         curvature` without file normals; per cloud):\n\n\
         | cloud | orientation (the summary) | decisive normals | facing the wrong way | pairs agree, printed | recount (`mls_ad::pair_agreement`) |\n\
         | --- | --- | --- | --- | --- | --- |\n",
    );
    let par = Parallelism::Rayon;
    for c in 0..cases {
        let seed = crate::validate::case_seed(base_seed ^ 0x6f72_6965_6e74, c as u64);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let shape = SHAPES[c % SHAPES.len()];
        let cloud = cloud(shape, &mut rng);
        let name = format!("{} (seed {seed:#x})", cloud.name);
        let index = mls_pipeline::pipeline::index(&cloud.points, Frame::of(&cloud.points), &name)?;
        let scale =
            mls_pipeline::pipeline::choose_h_on(&index, None, DEFAULT_H_FACTOR, par, &name)?;
        let normals = mls_pipeline::pipeline::normals(
            None,
            &cloud.points,
            Some(&index),
            NormalsMode::Estimate,
            cloud.orient,
            None,
            scale.h,
            par,
            &name,
        )?;
        // The side: among normals within 60° of the truth direction or its opposite (whose
        // sign the geometry decides), those facing away from it.
        let (mut decisive, mut wrong) = (0usize, 0usize);
        for (n, t) in normals.normals.iter().zip(&cloud.truth) {
            // No normal, or no truth (a box's point near a crease).
            let (Some(n), Some(t)) = (n, t.try_normalize(0.0)) else {
                continue;
            };
            let cosine = n.normalize().dot(&t);
            if cosine.abs() >= 0.5 {
                decisive += 1;
                wrong += usize::from(cosine < 0.0);
            }
        }
        let share = if decisive == 0 {
            1.0
        } else {
            wrong as f64 / decisive as f64
        };
        let row = match shape {
            Shape::Sphere | Shape::Ellipsoid | Shape::Torus | Shape::Cuboid => Q::OrientOutward,
            Shape::SheetDefault | Shape::SheetViewpoint => Q::OrientSheet,
        };
        tally.record(row, share, seed);
        let recount = mls_ad::pair_agreement(
            &cloud.points,
            &normals.normals,
            mls_ad::documented::NORMAL_NEIGHBOURS,
        );
        let expected = recount.share().map(|s| format!("{:.2}", 100.0 * s));
        let printed = printed_agreement(&normals.source);
        tally.record(
            Q::PairAgreement,
            f64::from(expected.as_deref() != printed),
            seed,
        );
        let rule = normals
            .source
            .split(" by minimum spanning tree")
            .next()
            .and_then(|s| s.split("), ").nth(1))
            .unwrap_or("?");
        writeln!(
            table,
            "| {name} | {rule} | {decisive} | {wrong} | {}% | {}% of {} |",
            printed.unwrap_or("none"),
            expected.as_deref().unwrap_or("none"),
            recount.compared
        )?;
    }
    Ok(table)
}
