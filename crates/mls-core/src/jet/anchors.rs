//! Shared supports: where noise makes the jet choose a degree-2 fit on a support many cells
//! wide, the fits of neighbouring points share all but a sliver of their samples, and the
//! estimate is a smooth function of the query on the scale of that support. There the curvature
//! of a query is blended from the jets of nearby **anchors** (one sample per cell of a grid)
//! instead of fitted again.
//!
//! - Anchors: the sample nearest the centre of each occupied cell of side
//!   `c` = [`ANCHOR_CELL`]·h, cells counted from the world origin (so that a tile of a larger
//!   cloud has the whole cloud's anchors), ties to the first in storage order.
//! - A query `x` is **shared** when at least [`ANCHOR_MIN_COUNT`] anchors lie within
//!   `R` = [`ANCHOR_REACH`]·c, and every one of them chose a degree-2 fit whose support radius
//!   is at least [`ANCHOR_MIN_SUPPORT`]·c, with a normal within [`ANCHOR_MAX_TURN`] of their
//!   weighted mean, and `x` lies within [`ANCHOR_RESIDUAL`] σ̂ of the nearest anchor's fitted
//!   quadric (σ̂ that fit's noise estimate): a query off the surface gets its own robust fit,
//!   which may flag it an outlier. Every other query gets its own jet.
//! - The blend: the anchors' shape tensors `k1 d1d1ᵀ + k2 d2d2ᵀ` averaged with the weights
//!   `(1 − d²/R²)²`, restricted to the tangent plane of the averaged normal and diagonalised
//!   ([`crate::curvature()`]); the predicted error and bias averaged with the same weights; the
//!   foot point `x` moved along the normal onto the nearest anchor's quadric.
//!
//! The blend's weights reach `R` = 3h while the supports are at least 6h: the blend is a
//! slightly wider smoothing of the same estimate. `docs/derivation.md` has the measurements
//! and `mls_ad::jet_share` recomputes it.

use kiddo::{ImmutableKdTree, SquaredEuclidean};

use crate::curvature::curvature;
use crate::field::Sample;
use crate::math::{Matrix, Point, Vector};

use super::JetPoint;

/// The anchors' cell side, in h.
pub const ANCHOR_CELL: f64 = 1.5;
/// The blend's radius, in cells.
pub const ANCHOR_REACH: f64 = 2.0;
/// The fewest anchors within reach for a blend.
pub const ANCHOR_MIN_COUNT: usize = 3;
/// The smallest support radius of an anchor's degree-2 fit that a blend takes, in cells.
pub const ANCHOR_MIN_SUPPORT: f64 = 4.0;
/// The cosine of the largest angle between an anchor's normal and the blend's.
pub const ANCHOR_MAX_TURN: f64 = 0.9;
/// The largest distance of a shared query from the nearest anchor's quadric, in that fit's σ̂.
pub const ANCHOR_RESIDUAL: f64 = 3.0;

/// The anchors of a cloud's samples (internal coordinates) and their k-d tree.
#[derive(Debug)]
pub struct Anchors {
    cell: f64,
    points: Vec<Point>,
    /// `None` only without anchors (the tree refuses an empty slice).
    tree: Option<ImmutableKdTree<f64, 3>>,
}

impl Anchors {
    /// The anchors of `samples` (stored relative to `origin`) at cell side `cell`.
    pub fn new(samples: &[Sample], origin: &Vector, cell: f64) -> Self {
        use std::collections::HashMap;
        let mut best: HashMap<[i64; 3], (f64, usize)> = HashMap::new();
        for (i, s) in samples.iter().enumerate() {
            let world = s.point.coords + origin;
            let scaled = world / cell;
            let key = [0, 1, 2].map(|k| scaled[k].floor() as i64);
            let centre = Vector::from(key.map(|k| (k as f64 + 0.5) * cell));
            let d2 = (world - centre).norm_squared();
            let entry = best.entry(key).or_insert((f64::INFINITY, usize::MAX));
            if d2 < entry.0 {
                *entry = (d2, i);
            }
        }
        let mut chosen: Vec<usize> = best.into_values().map(|(_, i)| i).collect();
        chosen.sort_unstable();
        let points: Vec<Point> = chosen.iter().map(|&i| samples[i].point).collect();
        let coords: Vec<[f64; 3]> = points.iter().map(|p| p.coords.into()).collect();
        let tree = ImmutableKdTree::new_from_slice(&coords).ok();
        Self { cell, points, tree }
    }

    /// Anchor `i`'s position (internal coordinates).
    pub fn point(&self, i: usize) -> &Point {
        &self.points[i]
    }

    /// The blend's radius.
    pub fn reach(&self) -> f64 {
        ANCHOR_REACH * self.cell
    }

    /// Appends to `out` the anchors within reach of `local` (internal coordinates) with their
    /// squared distances, in anchor order.
    pub fn near(&self, local: &Point, out: &mut Vec<(u32, f64)>) {
        let Some(tree) = &self.tree else {
            return;
        };
        let start = out.len();
        let r = self.reach();
        tree.query(&local.coords.into())
            .within::<SquaredEuclidean<f64>>(r * r)
            .unsorted()
            .visit(|hit| out.push((hit.item, hit.distance)));
        out[start..].sort_unstable_by_key(|&(i, _)| i);
    }

    /// The blended jet at `x` (world; `local` = `x − origin`, internal) from the anchors
    /// `near` (squared distance, the anchor's jet), or `None` where the query is not shared
    /// (see the module's rules).
    pub fn blend(
        &self,
        x: &Point,
        local: &Point,
        origin: &Vector,
        near: &[(f64, &JetPoint)],
    ) -> Option<JetPoint> {
        if near.len() < ANCHOR_MIN_COUNT {
            return None;
        }
        let r2 = self.reach() * self.reach();
        let min_support = ANCHOR_MIN_SUPPORT * self.cell;
        let mut normal = Vector::zeros();
        let mut weight = 0.0;
        let mut nearest: Option<(f64, &JetPoint)> = None;
        for &(d2, p) in near {
            if p.fit.degree != 2 || !(p.fit.radius >= min_support) {
                return None;
            }
            let t = 1.0 - d2 / r2;
            let w = t * t;
            normal += p.curvature.normal * w;
            weight += w;
            if nearest.is_none_or(|(n, _)| d2 < n) {
                nearest = Some((d2, p));
            }
        }
        let normal = normal.try_normalize(0.0)?;
        let mut shape = Matrix::zeros();
        let (mut sd, mut bias) = ([0.0; 2], [0.0; 2]);
        for &(d2, p) in near {
            let c = &p.curvature;
            if !(c.normal.dot(&normal) >= ANCHOR_MAX_TURN) {
                return None;
            }
            let t = 1.0 - d2 / r2;
            let w = t * t / weight;
            // The directions turned with the normal (about n_a × n, not projected, which
            // would shorten them by the cosine of the turn and shrink the curvature).
            let (d1, d2) = (
                turn(&c.d1, &c.normal, &normal),
                turn(&c.d2, &c.normal, &normal),
            );
            shape += (d1 * d1.transpose() * c.k1 + d2 * d2.transpose() * c.k2) * w;
            for i in 0..2 {
                sd[i] += p.sd[i] * w;
                bias[i] += p.bias[i].abs() * w;
            }
        }
        // The query's height above the nearest anchor's quadric `w = −(k1 s1² + k2 s2²)/2`
        // about its foot point.
        let (_, p) = nearest?;
        let c = &p.curvature;
        let d = local - (p.foot - origin);
        let (s1, s2) = (d.dot(&c.d1), d.dot(&c.d2));
        let residual = d.dot(&c.normal) + 0.5 * (c.k1 * s1 * s1 + c.k2 * s2 * s2);
        if !(residual.abs() <= ANCHOR_RESIDUAL * p.fit.noise) {
            return None;
        }
        let tangent = Matrix::identity() - normal * normal.transpose();
        let curvature = curvature(&normal, &(tangent * shape * tangent))?;
        Some(JetPoint {
            foot: x - c.normal * residual,
            curvature,
            sd,
            bias,
            fit: p.fit,
        })
    }
}

/// `v` turned by the least rotation taking the unit vector `from` to the unit vector `to`
/// (Rodrigues' formula, `from · to > 0`).
fn turn(v: &Vector, from: &Vector, to: &Vector) -> Vector {
    let axis = from.cross(to);
    let cos = from.dot(to);
    v * cos + axis.cross(v) + axis * (axis.dot(v) / (1.0 + cos))
}
