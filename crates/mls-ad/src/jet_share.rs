//! The witness of shared supports (`mls_core::jet`'s anchors, `docs/derivation.md`, "Shared
//! supports"): the anchors chosen by brute force over the samples in world coordinates, each
//! anchor's jet from [`crate::jet_witness`], and the blend by rotation matrices
//! (`Rotation3::rotation_between`, where production turns the directions by Rodrigues'
//! formula) and a 3 × 3 eigen-decomposition ([`crate::witness_curvature`]). Every rule is
//! restated from [`crate::documented`].

use std::collections::HashMap;

use mls_core::{JetConfig, NormalData, Sample};
use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::documented::{
    SHARE_CELL, SHARE_MAX_TURN, SHARE_MIN_COUNT, SHARE_MIN_SUPPORT, SHARE_REACH, SHARE_RESIDUAL,
};
use crate::jet::{JetRefusal, JetWitness, jet_witness};
use crate::witness_curvature;

/// The anchors of one cloud, with the witness's jets at those asked so far.
#[derive(Debug)]
pub struct ShareWitness<'a> {
    samples: &'a [Sample],
    h: f64,
    config: JetConfig,
    /// Indices of the anchor samples, increasing.
    anchors: Vec<usize>,
    jets: HashMap<usize, Result<JetWitness, JetRefusal>>,
}

impl<'a> ShareWitness<'a> {
    /// The anchors of `samples` (world coordinates) at scale `h`: in each occupied cell of the
    /// grid of side `SHARE_CELL·h` from the world origin, the sample nearest the cell's centre
    /// (the first of equals).
    pub fn new(samples: &'a [Sample], h: f64, config: &JetConfig) -> Self {
        let cell = SHARE_CELL * h;
        let mut best: HashMap<[i64; 3], usize> = HashMap::new();
        let centre_distance = |i: usize| {
            let p = samples[i].point.coords;
            let key = p.map(|c| (c / cell).floor());
            (p - (key.add_scalar(0.5) * cell)).norm_squared()
        };
        for (i, s) in samples.iter().enumerate() {
            let key = [0, 1, 2].map(|k| (s.point[k] / cell).floor() as i64);
            best.entry(key)
                .and_modify(|j| {
                    if centre_distance(i) < centre_distance(*j) {
                        *j = i;
                    }
                })
                .or_insert(i);
        }
        let mut anchors: Vec<usize> = best.into_values().collect();
        anchors.sort_unstable();
        Self {
            samples,
            h,
            config: *config,
            anchors,
            jets: HashMap::new(),
        }
    }

    fn jet(&mut self, i: usize) -> Result<JetWitness, JetRefusal> {
        let (samples, h, config) = (self.samples, self.h, self.config);
        *self
            .jets
            .entry(i)
            .or_insert_with(|| jet_witness(&samples[i].point.coords, samples, h, &config))
    }

    /// The blend at `x`, or `None` where `x` is not shared and gets its own jet (always, unless
    /// the configuration fits heights only with the degree-2 candidates and shares).
    pub fn shared(&mut self, x: &Vector3<f64>) -> Option<JetWitness> {
        let c = &self.config;
        if !(c.normals == NormalData::Ignore && c.quadratic && c.share) {
            return None;
        }
        let cell = SHARE_CELL * self.h;
        let reach2 = (SHARE_REACH * cell).powi(2);
        let near: Vec<(f64, usize)> = self
            .anchors
            .iter()
            .map(|&i| ((self.samples[i].point.coords - x).norm_squared(), i))
            .filter(|&(d2, _)| d2 <= reach2)
            .collect();
        if near.len() < SHARE_MIN_COUNT {
            return None;
        }
        let mut jets = Vec::with_capacity(near.len());
        for &(d2, i) in &near {
            // Stop at the first anchor that rules the blend out: on clean data that is the
            // first, so the witness costs one anchor's jet per query there.
            let w = self.jet(i).ok()?;
            if w.degree != 2 || w.radius < SHARE_MIN_SUPPORT * cell {
                return None;
            }
            jets.push(((1.0 - d2 / reach2).powi(2), w));
        }
        let total: f64 = jets.iter().map(|(w, _)| w).sum();
        let normal = jets
            .iter()
            .map(|(w, j)| j.normal * (*w / total))
            .sum::<Vector3<f64>>()
            .normalize();
        if jets
            .iter()
            .any(|(_, j)| j.normal.dot(&normal) < SHARE_MAX_TURN)
        {
            return None;
        }
        // The nearest anchor (the first of equals): its quadric holds the query or not.
        let (nearest, _) = near
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0))?;
        let j = &jets[nearest].1;
        let d = x - j.foot;
        let [s1, s2] = j.directions.map(|t| d.dot(&t));
        let height = d.dot(&j.normal) + 0.5 * (j.k1 * s1 * s1 + j.k2 * s2 * s2);
        if !(height.abs() <= SHARE_RESIDUAL * j.noise) {
            return None;
        }
        let mut shape = Matrix3::zeros();
        let (mut sd, mut bias) = ([0.0; 2], [0.0; 2]);
        for (w, a) in &jets {
            let w = w / total;
            let turn = Rotation3::rotation_between(&a.normal, &normal)?;
            let own = a.directions[0] * a.directions[0].transpose() * a.k1
                + a.directions[1] * a.directions[1].transpose() * a.k2;
            shape += turn.matrix() * own * turn.matrix().transpose() * w;
            for i in 0..2 {
                sd[i] += a.sd[i] * w;
                bias[i] += a.bias[i].abs() * w;
            }
        }
        let c = witness_curvature(&normal, &shape);
        Some(JetWitness {
            k1: c.k1,
            k2: c.k2,
            sd,
            bias,
            foot: x - j.normal * height,
            normal,
            directions: [c.d1, c.d2],
            condition: jets.iter().map(|(_, a)| a.condition).fold(0.0, f64::max),
            ..*j
        })
    }
}
