//! Tests of the generator: reproducibility, probes, first bad indices, similarity images.

use super::*;

#[test]
fn every_class_is_reproducible_and_well_formed() {
    for seed in 0..(4 * AdversarialClass::ALL.len() as u64) {
        let cloud = AdversarialCloud::from_seed(seed);
        // Debug output, not `==`: NaN coordinates are equal to themselves there.
        let again = AdversarialCloud::from_seed(seed);
        assert_eq!(format!("{cloud:?}"), format!("{again:?}"), "seed {seed}");
        assert_eq!(cloud.points.len(), cloud.normals.len(), "seed {seed}");
        assert!(cloud.h.is_finite() && cloud.h > 0.0, "seed {seed}");
        if let Some(c) = cloud.cutoff {
            assert!(c >= 2.0, "seed {seed}");
        }
        let needs_support = cloud
            .probes
            .iter()
            .any(|p| matches!(p.kind, ProbeKind::Void | ProbeKind::Alone));
        assert!(!needs_support || cloud.cutoff.is_some(), "seed {seed}");
    }
}

#[test]
fn probes_are_as_described() {
    for seed in 0..40 {
        let cloud = AdversarialCloud::generate(AdversarialClass::Isolated, seed);
        let radius = cloud.support_radius().unwrap();
        for probe in &cloud.probes {
            let near = cloud
                .points
                .iter()
                .filter(|p| (*p - probe.point).norm() <= 2.0 * radius)
                .count();
            let expected = match probe.kind {
                ProbeKind::Void => 0,
                _ => 1,
            };
            assert_eq!(near, expected, "seed {seed}: {probe:?}");
        }
    }
}

#[test]
fn non_finite_and_bad_normal_indices_are_the_first() {
    for seed in 0..40 {
        let cloud = AdversarialCloud::generate(AdversarialClass::NonFinite, seed);
        let Expectation::NonFinitePoint { index } = cloud.expectation else {
            panic!("seed {seed}: {:?}", cloud.expectation);
        };
        let first = cloud
            .points
            .iter()
            .position(|p| !p.iter().all(|c| c.is_finite()));
        assert_eq!(first, Some(index), "seed {seed}");
        let cloud = AdversarialCloud::generate(AdversarialClass::BadNormals, seed);
        if let Expectation::BadNormal { index } = cloud.expectation {
            let first = cloud
                .normals
                .iter()
                .position(|n| !n.iter().all(|c| c.is_finite()) || n.norm() <= f64::MIN_POSITIVE);
            assert_eq!(first, Some(index), "seed {seed}");
        }
    }
}

#[test]
fn matches_are_images_of_their_base() {
    for class in [
        AdversarialClass::Offset,
        AdversarialClass::ScaledDown,
        AdversarialClass::ScaledUp,
    ] {
        for seed in 0..10 {
            let cloud = AdversarialCloud::generate(class, seed);
            let Expectation::Matches {
                base,
                scale,
                offset,
            } = &cloud.expectation
            else {
                panic!("{class} seed {seed}");
            };
            assert_eq!(cloud.points.len(), base.points.len());
            assert_eq!(cloud.h, base.h * scale);
            for (p, q) in cloud.points.iter().zip(&base.points) {
                assert_eq!(p.coords, q.coords * *scale + offset);
            }
        }
    }
}
