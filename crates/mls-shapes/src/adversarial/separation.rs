//! Points too far apart or sheets too close together: isolated points and voids, opposite
//! sheets, a plate thinner than h.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::patch::{random_motion, random_unit, smooth_draft, usual_cutoff, usual_h};
use super::{Draft, Probe, ProbeKind};
use crate::math::{Point, Vector};

pub(super) fn isolated(rng: &mut ChaCha8Rng) -> Draft {
    let scattered = rng.random_bool(0.25);
    let mut draft = if scattered {
        Draft::new(
            "only scattered points",
            Vec::new(),
            rng.random_range(0.01..1.0),
        )
    } else {
        smooth_draft(rng, "patch with outliers")
    };
    let cutoff = usual_cutoff(rng);
    draft.cutoff = Some(cutoff);
    draft.cutoff_free = false;
    let radius = cutoff * draft.h;
    // Outliers on a lattice of pitch 3 radii far from the patch: every one is more than
    // twice the support radius from every other point, and so is the centre of every lattice
    // cell (a void probe).
    let far = draft
        .points
        .iter()
        .map(|(p, _)| p.coords.amax())
        .fold(0.0, f64::max)
        + 4.0 * radius;
    let pitch = 3.0 * radius;
    let count = rng.random_range(1..=12);
    let corner = Vector::repeat(far);
    for k in 0..count {
        let cell = Vector::new((k % 3) as f64, ((k / 3) % 2) as f64, (k / 6) as f64);
        let p = Point::from(corner + cell * pitch);
        draft.points.push((p, random_unit(rng)));
        draft.probes.push(Probe {
            point: p,
            kind: ProbeKind::Alone,
        });
        draft.probes.push(Probe {
            point: p + Vector::repeat(0.5 * pitch),
            kind: ProbeKind::Void,
        });
    }
    draft
}

pub(super) fn opposite_sheets(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let h = usual_h(rng, spacing);
    let gap = rng.random_range(0.05..2.0) * h;
    let m = rng.random_range(8..=20);
    let facing = rng.random_bool(0.5);
    let (rotation, t) = random_motion(rng, 5.0);
    let up = rotation * Vector::z();
    let sign = if facing { -1.0 } else { 1.0 };
    let mut points = Vec::new();
    for i in 0..m {
        for j in 0..m {
            let (x, y) = (i as f64 * spacing, j as f64 * spacing);
            points.push((rotation * Point::new(x, y, 0.5 * gap) + t, up * sign));
            points.push((rotation * Point::new(x, y, -0.5 * gap) + t, -up * sign));
        }
    }
    let mut draft = Draft::new(
        if facing {
            "normals facing each other"
        } else {
            "normals facing away"
        },
        points,
        h,
    );
    draft.cutoff = Some(usual_cutoff(rng));
    // Mid-plane probes away from the rim, where both sheets are within the support.
    let middle = (m - 1) as f64 * spacing * 0.5;
    for _ in 0..8 {
        let (x, y) = (
            middle + rng.random_range(-0.25..0.25) * middle,
            middle + rng.random_range(-0.25..0.25) * middle,
        );
        draft.probes.push(Probe {
            point: rotation * Point::new(x, y, 0.0) + t,
            kind: ProbeKind::Cancelling,
        });
    }
    draft
}

pub(super) fn thin_plate(rng: &mut ChaCha8Rng) -> Draft {
    let spacing = rng.random_range(0.01..0.2);
    let h = usual_h(rng, spacing);
    let thickness = rng.random_range(0.05..1.0) * h;
    let (nx, ny) = (rng.random_range(6..=16), rng.random_range(6..=16));
    let (lx, ly) = ((nx - 1) as f64 * spacing, (ny - 1) as f64 * spacing);
    let rows = ((thickness / spacing).ceil() as usize).max(1) + 1;
    let mut points = Vec::new();
    // Top and bottom faces.
    for i in 0..nx {
        for j in 0..ny {
            let (x, y) = (i as f64 * spacing, j as f64 * spacing);
            points.push((Point::new(x, y, thickness), Vector::z()));
            points.push((Point::new(x, y, 0.0), -Vector::z()));
        }
    }
    // The four sides, with `rows` rows across the thickness, corners excluded.
    for r in 0..rows {
        let z = thickness * r as f64 / (rows - 1).max(1) as f64;
        for i in 1..nx - 1 {
            let x = i as f64 * spacing;
            points.push((Point::new(x, 0.0, z), -Vector::y()));
            points.push((Point::new(x, ly, z), Vector::y()));
        }
        for j in 1..ny - 1 {
            let y = j as f64 * spacing;
            points.push((Point::new(0.0, y, z), -Vector::x()));
            points.push((Point::new(lx, y, z), Vector::x()));
        }
    }
    let (rotation, t) = random_motion(rng, 5.0);
    let points = points
        .into_iter()
        .map(|(p, n)| (rotation * p + t, rotation * n))
        .collect();
    let mut draft = Draft::new("closed plate thinner than h", points, h);
    draft.cutoff = Some(usual_cutoff(rng));
    draft
}
