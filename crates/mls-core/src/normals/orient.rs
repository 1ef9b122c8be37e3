//! Consistent orientation of estimated normals (Hoppe et al. 1992).
//!
//! Here the rules ([`Orientation`]), what an orientation reports and the entry points;
//! `orient/tree.rs` holds the spanning forest and its traversal, `orient/checks.rs` the
//! checks of the result ([`orientation_consistency`] and the facing count).

mod checks;
mod tree;

use checks::{consistency_of, facing_of};
pub use checks::{orientation_consistency, sampled_consistency};
use tree::orient_along_tree;

use super::{NeighbourGraph, NormalEstimate, NormalsError, check_points};
use crate::math::{Point, Vector};
use crate::par::Parallelism;
use crate::status::PointStatus;

/// How [`orient_normals`] chooses the sign of each connected component.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Orientation {
    /// Leave the signs as estimated (arbitrary). For callers who orient by other means.
    None,
    /// Away from the component: the seed of each component is the point where the normal line
    /// passes farthest from the component's centroid `c`, i.e. the maximiser of
    /// `|n_i · (p_i − c)| · confidence_i`, and its normal gets `n · (p − c) > 0`. For a
    /// closed surface that is star-shaped about its centroid this makes every normal point
    /// out. A flat component (every normal line passing within 10⁻⁶ of its extent of the
    /// centroid) has no outside; its seed normal is chosen with a positive component along its
    /// largest axis, for determinism.
    #[default]
    Outward,
    /// Towards a viewpoint `v` (the scanner position), by a weighted vote. The spanning
    /// tree of each component is cut into smooth patches at its edges between normals more
    /// than about 26° apart (creases, see [`orient_normals`]); inside a patch the signs are
    /// made consistent along the tree, and the patch is flipped as a whole when
    ///
    /// $$ \sum_{i \in \text{patch}} \mathbf n_i \cdot
    ///    \frac{\mathbf v - \mathbf p_i}{|\mathbf v - \mathbf p_i|} < 0, $$
    ///
    /// i.e. every point votes with the cosine between its normal and its line of sight. A
    /// normal seen face-on votes with weight 1, one seen edge-on (a wall seen from far above)
    /// with weight about 0, so the points whose sign the viewpoint cannot tell do not decide.
    /// A tie keeps the sign the tree carries into the patch.
    ///
    /// The rule assumes the cloud was scanned from `v`, so that every point faces it. It does
    /// not suit a closed object sampled all round: over a closed surface the votes cancel
    /// (the flux of a unit field), and [`Outward`](Self::Outward) is the rule for it.
    /// (Before, each component was seeded at its single point closest to `v`; on an aerial
    /// tile that was a wall-edge point seen edge-on whose sign turned with the height of the
    /// viewpoint, and with it the whole tile.)
    Viewpoint(Point),
    /// Upwards, for airborne scans and terrain: the same patches and vote as
    /// [`Viewpoint`](Self::Viewpoint) with the line of sight `+z` everywhere (a viewpoint
    /// infinitely far above): a patch is flipped when `Σ n_z < 0` over it. Roofs and ground
    /// point up; walls take the sign of their patch's slight tilt, or of the tree where the
    /// tilt is nil.
    Up,
}

impl Orientation {
    /// The unit direction the normal at `p` should face under a voting rule
    /// ([`Viewpoint`](Self::Viewpoint), [`Up`](Self::Up)); `None` for the other rules and for
    /// a point at the viewpoint itself, which has no line of sight.
    pub fn line_of_sight(&self, p: &Point) -> Option<Vector> {
        match self {
            Self::Viewpoint(v) => {
                let d = v - p;
                // Scaled by the largest component first, so that neither a far viewpoint nor
                // a tiny offset over- or underflows the norm.
                let m = d.amax();
                (m > 0.0 && m.is_finite()).then(|| {
                    let d = d / m;
                    d / d.norm()
                })
            }
            Self::Up => Some(Vector::z()),
            Self::None | Self::Outward => None,
        }
    }

    /// Whether this rule orients by the vote of [`line_of_sight`](Self::line_of_sight).
    fn votes(&self) -> bool {
        matches!(self, Self::Viewpoint(_) | Self::Up)
    }
}

/// For the voting rules, how well the oriented normals follow the rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facing {
    /// Oriented normals with a line of sight.
    pub normals: usize,
    /// Among them, those that face it (`n · u > 0`).
    pub facing: usize,
    /// Oriented normals within 60° of the line of sight or its opposite (`|n · u| ≥ 1/2`):
    /// those whose sign the viewpoint decides clearly.
    pub decisive: usize,
    /// Among them, those that face it.
    pub decisive_facing: usize,
}

impl Facing {
    /// `facing / normals`, `None` without normals.
    pub fn share(&self) -> Option<f64> {
        (self.normals > 0).then(|| self.facing as f64 / self.normals as f64)
    }

    /// `decisive_facing / decisive`, `None` without decisive normals.
    pub fn decisive_share(&self) -> Option<f64> {
        (self.decisive > 0).then(|| self.decisive_facing as f64 / self.decisive as f64)
    }
}

/// What [`orient_normals`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientationReport {
    /// Points with an estimated normal (the nodes of the orientation graph).
    pub oriented: usize,
    /// Connected components of the graph among those points, each seeded on its own; 0 for
    /// [`Orientation::None`], which builds no tree.
    pub components: usize,
    /// Pieces of the spanning forest each given its sign on its own: the components for
    /// [`Orientation::Outward`]; for the voting rules, the smooth patches the components are
    /// cut into at creases (see [`orient_normals`]); 0 for [`Orientation::None`].
    pub patches: usize,
    /// Normals whose sign was changed.
    pub flipped: usize,
    /// [`orientation_consistency`] after orientation; `None` when no edge joins two points
    /// with normals.
    pub consistency: Option<f64>,
    /// For [`Orientation::Viewpoint`] and [`Orientation::Up`], the check of the rule itself:
    /// how many normals face their line of sight. `None` for the other rules.
    pub facing: Option<Facing>,
}

/// Orients normals consistently along a minimum spanning tree of the neighbour graph.
///
/// The graph is symmetrised (an edge joins `i` and `j` when either is among the other's
/// neighbours) and restricted to points with a normal. Edge weights
///
/// $$ w_{ij} = 1 - |\mathbf n_i \cdot \mathbf n_j| $$
///
/// are small between nearly parallel normals, so the minimum spanning tree (Kruskal, on the
/// edges sorted in parallel) propagates the sign across flat regions first and crosses
/// sharp bends last (Hoppe et al. 1992). From a seed in each connected component, a child's
/// normal is flipped when `n_child · n_parent < 0`. `orientation` then fixes the one sign left
/// per piece: for [`Orientation::Outward`] per component, from the seed chosen for it; for
/// [`Orientation::Viewpoint`] and [`Orientation::Up`] per smooth patch (the tree cut where
/// `|n_child · n_parent| < 0.9`), by the vote of the patch's points.
///
/// Points whose estimate failed are skipped and left failed. Deterministic: the result does
/// not depend on `par`.
pub fn orient_normals(
    points: &[Point],
    graph: &NeighbourGraph,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    orientation: Orientation,
    par: Parallelism,
) -> Result<OrientationReport, NormalsError> {
    let n = points.len();
    check_lengths(n, graph.len(), "graph nodes")?;
    check_lengths(n, estimates.len(), "normals")?;
    if let Orientation::Viewpoint(v) = orientation
        && !v.iter().all(|c| c.is_finite())
    {
        return Err(NormalsError::InvalidViewpoint);
    }
    orient_by_rule(points, graph, estimates, Rule::Fixed(orientation), par)
}

/// [`orient_normals`] and [`orient_normals_towards`] after their own checks.
fn orient_by_rule(
    points: &[Point],
    graph: &NeighbourGraph,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    rule: Rule<'_>,
    par: Parallelism,
) -> Result<OrientationReport, NormalsError> {
    let n = points.len();
    check_lengths(n, graph.len(), "graph nodes")?;
    check_lengths(n, estimates.len(), "normals")?;
    check_points(points)?;
    let k = graph.k();
    // Edges are numbered `i·k + slot` in 32 bits so that a sort key is one u64.
    let edge_ids = n.saturating_mul(k);
    if edge_ids > 1 << 32 {
        return Err(NormalsError::GraphTooLarge(edge_ids));
    }
    let oriented = estimates.iter().filter(|e| e.is_ok()).count();
    let (components, patches, flipped) = match rule {
        Rule::Fixed(Orientation::None) => (0, 0, 0),
        _ => orient_along_tree(points, graph, estimates, rule, par),
    };
    let consistency = consistency_of(points, graph, par, |i| {
        estimates
            .get(i)
            .and_then(|e| e.as_ref().ok())
            .map(|e| e.normal.into_inner())
    });
    let facing = rule.votes().then(|| {
        facing_of(points, rule, par, |i| {
            estimates
                .get(i)
                .and_then(|e| e.as_ref().ok())
                .map(|e| e.normal.into_inner())
        })
    });
    Ok(OrientationReport {
        oriented,
        components,
        patches,
        flipped,
        consistency,
        facing,
    })
}

/// Orients normals as [`orient_normals`] does for [`Orientation::Viewpoint`], with a viewpoint
/// per point: `viewpoints[i]` is the position of the scanner that measured point `i` (the
/// scans of an E57 file, each from its own pose). The same patches and the same vote, each
/// point voting with the cosine between its normal and its own line of sight
/// `(v_i − p_i)/|v_i − p_i|`:
///
/// $$ \sum_{i \in \text{patch}} \mathbf n_i \cdot
///    \frac{\mathbf v_i - \mathbf p_i}{|\mathbf v_i - \mathbf p_i|} < 0
///    \implies \text{flip the patch}. $$
///
/// A surface seen from several scanners is seen from the same side by all of them, so the
/// points of different scans in one patch agree. [`OrientationReport::facing`] counts the
/// normals facing their own scanner.
///
/// # Errors
/// Those of [`orient_normals`]; [`NormalsError::LengthMismatch`] when `viewpoints` does not
/// have one entry per point, and [`NormalsError::InvalidViewpoint`] for a non-finite one.
pub fn orient_normals_towards(
    points: &[Point],
    graph: &NeighbourGraph,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    viewpoints: &[Point],
    par: Parallelism,
) -> Result<OrientationReport, NormalsError> {
    check_lengths(points.len(), viewpoints.len(), "viewpoints")?;
    if !viewpoints.iter().all(|v| v.iter().all(|c| c.is_finite())) {
        return Err(NormalsError::InvalidViewpoint);
    }
    orient_by_rule(points, graph, estimates, Rule::PerPoint(viewpoints), par)
}

/// The sign rule of the tree traversal: one [`Orientation`] for all points, or a viewpoint per
/// point ([`orient_normals_towards`]).
#[derive(Clone, Copy)]
enum Rule<'a> {
    Fixed(Orientation),
    PerPoint(&'a [Point]),
}

impl Rule<'_> {
    /// The unit direction the normal of point `i` at `p` should face, for the voting rules.
    fn line_of_sight(&self, i: usize, p: &Point) -> Option<Vector> {
        match self {
            Self::Fixed(o) => o.line_of_sight(p),
            Self::PerPoint(v) => Orientation::Viewpoint(*v.get(i)?).line_of_sight(p),
        }
    }

    /// Whether this rule decides patches by the vote of [`line_of_sight`](Self::line_of_sight).
    fn votes(&self) -> bool {
        match self {
            Self::Fixed(o) => o.votes(),
            Self::PerPoint(_) => true,
        }
    }
}

fn check_lengths(points: usize, other: usize, what: &'static str) -> Result<(), NormalsError> {
    if points == other {
        Ok(())
    } else {
        Err(NormalsError::LengthMismatch {
            points,
            other,
            what,
        })
    }
}

/// Whether the directed edge `i → j` represents the undirected pair: always when `i < j`, and
/// when `i > j` only if `j → i` does not exist. Counts each pair once without a hash set.
fn is_canonical(graph: &NeighbourGraph, i: usize, j: usize) -> bool {
    i < j || !graph.neighbours(j).contains(&(i as u32))
}
