//! The climb of the degree-4 ladder at one query ([`Climb`]) and the frames the jet's fits take
//! from the samples' normals ([`frame_of_normals`]); the evaluator gathers the supports and
//! fits them (`Evaluator::jet_at`), these rules decide what each fit means for the climb.

use crate::field::Sample;
use crate::math::{Point, UnitNormal, Vector};
use crate::status::PointStatus;

use super::{JetFit, JetPoint, choose_scale_with_mse, frame, past_optimum, trusted};

/// What the climb does after a scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// Fit the next scale.
    Climb,
    /// The ladder is done.
    Stop,
}

/// The state of the ladder at one query: its fits so far, the intersection of their
/// confidence intervals and why it failed where no fit counts.
#[derive(Debug)]
pub struct Climb {
    /// The fits that count, in increasing radius (the evaluator's buffer, lent for the climb).
    ladder: Vec<JetPoint>,
    /// Full-degree fits with too few equations to trust their own noise estimate: candidates
    /// for the choice at the front of the ladder, outside its stopping rules.
    early: usize,
    /// Whether a trusted full-degree scale has been accepted.
    climbing: bool,
    /// Whether the last fit's interval met the others'.
    agree_last: bool,
    /// The intersection of the accepted fits' intervals `k ± Γ sd`, for k1 and k2.
    lo: [f64; 2],
    hi: [f64; 2],
    /// A lower-degree fit, for a point where no scale determines the full degree.
    fallback: Option<JetPoint>,
    failure: PointStatus,
}

impl Climb {
    /// A climb from no fit, in `ladder` (cleared).
    pub fn new(mut ladder: Vec<JetPoint>) -> Self {
        ladder.clear();
        Self {
            ladder,
            early: 0,
            climbing: false,
            agree_last: true,
            lo: [f64::NEG_INFINITY; 2],
            hi: [f64::INFINITY; 2],
            fallback: None,
            failure: PointStatus::NoNeighbours,
        }
    }

    /// A scale with `inside` samples, fewer than a fit needs.
    pub fn too_few(&mut self, inside: usize) {
        self.failure = if inside == 0 {
            PointStatus::NoNeighbours
        } else {
            PointStatus::TooFewNeighbours
        };
    }

    /// A scale whose fit failed: the ladder ends there once it has climbed.
    pub fn no_fit(&mut self) -> Step {
        if self.climbing {
            Step::Stop
        } else {
            self.failure = PointStatus::TooFewNeighbours;
            Step::Climb
        }
    }

    /// A fit whose surface has no gradient at the query.
    pub fn no_curvature(&mut self) -> Step {
        self.failure = PointStatus::GradientVanishes;
        Step::Stop
    }

    /// A scale's fit and its curvature `p`, of the full degree `full` or not.
    ///
    /// Fits of a lower degree have a bias of another order: the ladder proper starts at the
    /// first scale that determines the full degree, and a lower-degree fit is kept only for a
    /// point where no scale does (sparse or boundary neighbourhoods). The ladder climbs while
    /// the intervals `k ± confidence · sd` of all its scales intersect and [`past_optimum`]
    /// does not stop it.
    pub fn offer(&mut self, p: JetPoint, fit: &JetFit, full: bool, confidence: f64) -> Step {
        if !self.climbing && !full {
            self.fallback = self.fallback.or(Some(p));
            return Step::Climb;
        }
        if !self.climbing && !trusted(fit) {
            self.ladder.push(p);
            self.early += 1;
            return Step::Climb;
        }
        let mut agree = true;
        for (i, k) in [p.curvature.k1, p.curvature.k2].into_iter().enumerate() {
            self.lo[i] = self.lo[i].max(k - confidence * p.sd[i]);
            self.hi[i] = self.hi[i].min(k + confidence * p.sd[i]);
            agree &= self.lo[i] <= self.hi[i];
        }
        self.ladder.push(p);
        self.agree_last = agree;
        if !agree {
            return Step::Stop;
        }
        self.climbing = true;
        if past_optimum(&self.ladder[self.early..]) {
            Step::Stop
        } else {
            Step::Climb
        }
    }

    /// The λ the ladder's first fit found, for the fits after it; none where that fit had no
    /// slope to weigh (λ = 0), so that a later scale with slopes weighs its own.
    pub fn slope_weight(&self) -> Option<f64> {
        self.ladder
            .first()
            .map(|p| p.fit.slope_weight)
            .filter(|&l| l > 0.0)
    }

    /// Whether any fit is a candidate for the choice (a lead scale joins only then).
    pub fn has_candidates(&self) -> bool {
        self.accepted() > 0
    }

    fn accepted(&self) -> usize {
        if self.climbing {
            self.ladder.len() - usize::from(!self.agree_last)
        } else {
            self.early
        }
    }

    /// The buffer, back to the caller, where the query ends before any choice.
    pub fn release(self) -> Vec<JetPoint> {
        self.ladder
    }

    /// The choice of least estimated squared error among the candidates and `lead` (a fit on
    /// a smaller support, taken only where there are candidates), with that error; a
    /// lower-degree fallback has none (infinite). The buffer goes back to the caller.
    pub fn choose(
        mut self,
        lead: Option<JetPoint>,
    ) -> (Vec<JetPoint>, Result<(f64, JetPoint), PointStatus>) {
        let mut accepted = self.accepted();
        let choice = if accepted == 0 {
            self.fallback
                .map(|p| (f64::INFINITY, p))
                .ok_or(self.failure)
        } else {
            if let Some(p) = lead {
                self.ladder.insert(0, p);
                accepted += 1;
            }
            Ok(choose_scale_with_mse(&self.ladder, accepted))
        };
        (self.ladder, choice)
    }
}

/// The frame of the samples' normals averaged with the jet's weights `(1 − d²/ρ²)³` about
/// `centre`, with its tangent basis; where that average is over 60° from `own` (across a thin
/// part, where the far sheet's normals are opposed), the average of only the normals facing
/// `own`. `None` where the average vanishes.
pub fn frame_of_normals(
    samples: &[Sample],
    centre: &Point,
    radius: f64,
    own: &Vector,
) -> Option<(Vector, Vector, Vector)> {
    let inv_r2 = 1.0 / (radius * radius);
    let weighted = |s: &Sample| {
        let t = (1.0 - (s.point - centre).norm_squared() * inv_r2).max(0.0);
        s.normal * (t * t * t)
    };
    let sum: Vector = samples.iter().map(weighted).sum();
    let sum = if sum.dot(own) > 0.5 * sum.norm() * own.norm() {
        sum
    } else {
        samples
            .iter()
            .filter(|s| s.normal.dot(own) > 0.0)
            .map(weighted)
            .sum()
    };
    UnitNormal::new(sum).ok().map(|n| frame(&n.into_inner()))
}

/// The normal of the sample nearest `centre` (the first of equals), zero where there is none.
pub fn nearest_normal(samples: &[Sample], centre: &Point) -> Vector {
    let (mut nearest, mut own) = (f64::INFINITY, Vector::zeros());
    for s in samples {
        let d2 = (s.point - centre).norm_squared();
        if d2 < nearest {
            (nearest, own) = (d2, s.normal);
        }
    }
    own
}
