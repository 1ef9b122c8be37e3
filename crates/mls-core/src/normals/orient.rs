//! Consistent orientation of estimated normals (Hoppe et al. 1992).

use rayon::prelude::*;

use super::{NeighbourGraph, NormalEstimate, NormalsError, bounding_box_centre, check_points};
use crate::math::{Point, Vector};
use crate::status::PointStatus;
use crate::surface::Parallelism;

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
    let consistency = consistency_of(graph, par, |i| {
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

/// The fraction of graph edges whose normals agree in sign, `n_i · n_j > 0`.
///
/// Edges are those of the symmetrised graph, each pair counted once, and only between points
/// whose normals are finite and non-zero (a zero normal marks a missing one). A consistently
/// oriented smooth, well-sampled surface scores 1; random signs score about 0.5. Returns
/// `Ok(None)` when no edge qualifies. The normals need not be unit length.
pub fn orientation_consistency(
    graph: &NeighbourGraph,
    normals: &[Vector],
    par: Parallelism,
) -> Result<Option<f64>, NormalsError> {
    check_lengths(graph.len(), normals.len(), "normals")?;
    Ok(consistency_of(graph, par, |i| {
        normals
            .get(i)
            .filter(|v| v.iter().all(|c| c.is_finite()) && v.norm_squared() > 0.0)
            .copied()
    }))
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

fn consistency_of<F>(graph: &NeighbourGraph, par: Parallelism, normal: F) -> Option<f64>
where
    F: Fn(usize) -> Option<Vector> + Sync,
{
    let count = |i: usize| -> (usize, usize) {
        let Some(ni) = normal(i) else {
            return (0, 0);
        };
        graph
            .neighbours(i)
            .iter()
            .map(|&j| j as usize)
            .filter(|&j| j != i && is_canonical(graph, i, j))
            .filter_map(&normal)
            .fold((0, 0), |(all, agree), nj| {
                (all + 1, agree + usize::from(ni.dot(&nj) > 0.0))
            })
    };
    let add = |a: (usize, usize), b: (usize, usize)| (a.0 + b.0, a.1 + b.1);
    let (all, agree) = par.sum(graph.len(), 1024, (0, 0), count, add);
    (all > 0).then(|| agree as f64 / all as f64)
}

/// How many of the normals face their line of sight under `rule` (a voting rule).
fn facing_of<F>(points: &[Point], rule: Rule<'_>, par: Parallelism, normal: F) -> Facing
where
    F: Fn(usize) -> Option<Vector> + Sync,
{
    let count = |i: usize| -> [usize; 4] {
        let (Some(n), Some(u)) = (
            normal(i),
            points.get(i).and_then(|p| rule.line_of_sight(i, p)),
        ) else {
            return [0; 4];
        };
        let c = n.dot(&u);
        let decisive = c.abs() >= 0.5;
        [
            1,
            usize::from(c > 0.0),
            usize::from(decisive),
            usize::from(decisive && c > 0.0),
        ]
    };
    let add = |a: [usize; 4], b: [usize; 4]| [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]];
    let [normals, facing, decisive, decisive_facing] =
        par.sum(points.len(), 1024, [0; 4], count, add);
    Facing {
        normals,
        facing,
        decisive,
        decisive_facing,
    }
}

/// Kruskal's minimum spanning forest, then a traversal of each tree from its seed.
/// Returns (components, patches, flipped).
fn orient_along_tree(
    points: &[Point],
    graph: &NeighbourGraph,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    rule: Rule<'_>,
    par: Parallelism,
) -> (usize, usize, usize) {
    let n = points.len();
    let k = graph.k();
    let flat = graph.as_flat();
    let normal = |e: &[Result<NormalEstimate, PointStatus>], i: usize| {
        e.get(i)
            .and_then(|e| e.as_ref().ok())
            .map(|e| e.normal.into_inner())
    };

    // Sort key: the f32 weight's bits (order-preserving for non-negative floats) above the
    // edge number. Keys are unique, so the unstable sort is deterministic.
    let est: &[_] = estimates;
    let keys_of = |i: usize| {
        let ni = normal(est, i);
        flat.get(i * k..(i + 1) * k)
            .unwrap_or(&[])
            .iter()
            .enumerate()
            .filter_map(move |(slot, &j)| {
                let (ni, j) = (ni?, j as usize);
                if j == i || !is_canonical(graph, i, j) {
                    return None;
                }
                let nj = normal(est, j)?;
                let w = (1.0 - ni.dot(&nj).abs()).max(0.0) as f32;
                Some((u64::from(w.to_bits()) << 32) | (i * k + slot) as u64)
            })
    };
    let mut keys = edge_keys(n, par, keys_of);
    par.sort_unstable(&mut keys);

    let oriented = est.iter().filter(|e| e.is_ok()).count();
    let mut sets = DisjointSets::new(n);
    let mut tree: Vec<(u32, u32)> = Vec::with_capacity(oriented.saturating_sub(1));
    for key in keys {
        let id = (key & u64::from(u32::MAX)) as usize;
        let (i, j) = (id / k, flat[id] as usize);
        if sets.union(i, j) {
            tree.push((i as u32, j as u32));
            if tree.len() + 1 == oriented {
                break;
            }
        }
    }

    // Adjacency of the forest in compressed rows.
    let mut offsets = vec![0_usize; n + 1];
    for &(a, b) in &tree {
        offsets[a as usize + 1] += 1;
        offsets[b as usize + 1] += 1;
    }
    for i in 0..n {
        offsets[i + 1] += offsets[i];
    }
    let mut cursor = offsets.clone();
    let mut adjacent = vec![0_u32; 2 * tree.len()];
    for &(a, b) in &tree {
        adjacent[cursor[a as usize]] = b;
        cursor[a as usize] += 1;
        adjacent[cursor[b as usize]] = a;
        cursor[b as usize] += 1;
    }

    let seeds = choose_seeds(points, est, &mut sets, rule);
    let components = seeds.len();

    let votes = rule.votes();
    // Tree edges across which the sign is carried inside a patch: all of them for the outward
    // rule, only those between nearly parallel normals for the voting rules.
    let crease = if votes {
        CREASE_COSINE
    } else {
        f64::NEG_INFINITY
    };
    let mut flipped = 0;
    let mut patches = 0;
    let mut visited = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    // Seeds of the patches still to do, each with the tree neighbour it was reached from.
    let mut patch_seeds: Vec<(u32, u32)> = Vec::new();
    // The points of the current patch, for the vote.
    let mut members: Vec<u32> = Vec::new();
    for (seed, flip_seed) in seeds {
        if flip_seed {
            flip(&mut estimates[seed]);
            flipped += 1;
        }
        visited[seed] = true;
        patch_seeds.push((seed as u32, seed as u32));
        while let Some((start, from)) = patch_seeds.pop() {
            let (start, from) = (start as usize, from as usize);
            patches += 1;
            let mut patch_flips = 0;
            // Carry the sign from the neighbour that is final by now, so that a patch whose
            // vote is a tie keeps the sign the tree gives it.
            if from != start
                && let (Some(ns), Some(nf)) = (normal(estimates, start), normal(estimates, from))
                && ns.dot(&nf) < 0.0
            {
                flip(&mut estimates[start]);
                patch_flips += 1;
            }
            stack.push(start as u32);
            members.clear();
            // A node's sign is final when it is discovered, so depth-first order is as good
            // as breadth-first and needs no queue.
            while let Some(u) = stack.pop() {
                let u = u as usize;
                let Some(nu) = normal(estimates, u) else {
                    continue;
                };
                members.push(u as u32);
                for &w in &adjacent[offsets[u]..offsets[u + 1]] {
                    let w = w as usize;
                    if visited[w] {
                        continue;
                    }
                    visited[w] = true;
                    let Some(nw) = normal(estimates, w) else {
                        continue;
                    };
                    let dot = nw.dot(&nu);
                    if dot.abs() < crease {
                        patch_seeds.push((w as u32, u as u32));
                        continue;
                    }
                    if dot < 0.0 {
                        flip(&mut estimates[w]);
                        patch_flips += 1;
                    }
                    stack.push(w as u32);
                }
            }
            if votes && patch_vote(points, estimates, &members, rule) < 0.0 {
                for &i in &members {
                    flip(&mut estimates[i as usize]);
                }
                // Points flipped along the tree are now back to their estimated sign.
                patch_flips = members.len() - patch_flips;
            }
            flipped += patch_flips;
        }
    }
    (components, patches, flipped)
}

/// `|n_i · n_j|` below which a tree edge ends a patch of the voting rules: normals more than
/// about 26° from parallel.
///
/// Two neighbours about one spacing `s` apart whose normals differ by 26° sit on a bend of
/// radius below about 2.2 s, which is the default Gaussian scale `h = 2 s`: a bend the MLS
/// surface does not resolve (a roof meeting a wall, a parapet, foliage, noise). The sign the
/// tree carries across such an edge is unreliable, and on the LiDAR tile of the README a
/// chain of a few 50° edges turned whole roofs over (at 1/2, 60°, 3.2 % of the near-level
/// normals ended up downwards; at 0.9, 0.01 %). Inside a patch the tree is kept, so the
/// normals stay consistent where the surface is smooth.
const CREASE_COSINE: f64 = 0.9;

/// The vote of a patch's points under a voting rule: the sum over its normals of the cosine
/// between the normal and the point's line of sight. Points without a line of sight (at the
/// viewpoint itself) abstain.
fn patch_vote(
    points: &[Point],
    estimates: &[Result<NormalEstimate, PointStatus>],
    members: &[u32],
    rule: Rule<'_>,
) -> f64 {
    members
        .iter()
        .map(|&i| i as usize)
        .filter_map(|i| {
            let n = estimates.get(i)?.as_ref().ok()?.normal.into_inner();
            Some(n.dot(&rule.line_of_sight(i, points.get(i)?)?))
        })
        .sum()
}

/// Points per block of [`edge_keys`].
const KEY_BLOCK: usize = 4096;

/// The keys `keys_of(i)` of every point `i < n`, in point order, written in place.
///
/// A rayon `flat_map_iter(..).collect()` of an unknown total length collects per-thread
/// vectors and then copies them into the result, so the keys (8 bytes per edge, about half
/// the neighbour graph) were held twice at the peak of the orientation. Here the keys are
/// counted per block of points first, then each block fills its own slice of one vector of
/// the exact length.
fn edge_keys<F, I>(n: usize, par: Parallelism, keys_of: F) -> Vec<u64>
where
    F: Fn(usize) -> I + Sync,
    I: Iterator<Item = u64>,
{
    let block = |b: usize| b * KEY_BLOCK..((b + 1) * KEY_BLOCK).min(n);
    let blocks = n.div_ceil(KEY_BLOCK);
    let count = |b: usize| block(b).map(|i| keys_of(i).count()).sum::<usize>();
    let counts: Vec<usize> = par.map(blocks, 1, count);
    let mut keys = vec![0_u64; counts.iter().sum()];
    let mut slices: Vec<(usize, &mut [u64])> = Vec::with_capacity(blocks);
    let mut rest = keys.as_mut_slice();
    for (b, &c) in counts.iter().enumerate() {
        let (head, tail) = rest.split_at_mut(c);
        slices.push((b, head));
        rest = tail;
    }
    let fill = |(b, out): (usize, &mut [u64])| {
        for (slot, key) in out.iter_mut().zip(block(b).flat_map(&keys_of)) {
            *slot = key;
        }
    };
    match par {
        Parallelism::Sequential => slices.into_iter().for_each(fill),
        Parallelism::Rayon => slices.into_par_iter().for_each(fill),
    }
    keys
}

fn flip(e: &mut Result<NormalEstimate, PointStatus>) {
    if let Ok(e) = e {
        e.normal = -e.normal;
    }
}

/// Per component of the forest in `sets`: the seed point and whether its normal must flip.
fn choose_seeds(
    points: &[Point],
    estimates: &[Result<NormalEstimate, PointStatus>],
    sets: &mut DisjointSets,
    rule: Rule<'_>,
) -> Vec<(usize, bool)> {
    /// Relative size of the largest normal-line offset below which a component counts as
    /// flat (no outside).
    const FLAT: f64 = 1e-6;

    #[derive(Clone, Copy)]
    struct Component {
        sum: Vector,
        count: usize,
        seed: usize,
        score: f64,
        extent: f64,
    }

    let origin = bounding_box_centre(points);
    let mut component_of_root = vec![u32::MAX; points.len()];
    let mut components: Vec<Component> = Vec::new();
    let mut member: Vec<(usize, usize)> = Vec::new();
    for (i, e) in estimates.iter().enumerate() {
        if e.is_err() {
            continue;
        }
        let root = sets.find(i);
        if component_of_root[root] == u32::MAX {
            component_of_root[root] = components.len() as u32;
            components.push(Component {
                sum: Vector::zeros(),
                count: 0,
                seed: i,
                score: f64::NEG_INFINITY,
                extent: 0.0,
            });
        }
        let c = component_of_root[root] as usize;
        components[c].sum += points[i].coords - origin;
        components[c].count += 1;
        member.push((i, c));
    }

    for &(i, c) in &member {
        let Ok(e) = &estimates[i] else { continue };
        let comp = &mut components[c];
        let score = if rule.votes() {
            // The vote decides the sign, so any seed will do: the most confident one.
            e.confidence()
        } else {
            let centroid = comp.sum / comp.count as f64;
            let r = points[i].coords - origin - centroid;
            comp.extent = comp.extent.max(r.norm());
            e.normal.as_vector().dot(&r).abs() * e.confidence()
        };
        // Strictly greater keeps the lowest index among ties.
        if score > comp.score {
            comp.score = score;
            comp.seed = i;
        }
    }

    components
        .iter()
        .map(|comp| {
            let i = comp.seed;
            let n = estimates[i]
                .as_ref()
                .map(|e| e.normal.into_inner())
                .unwrap_or_else(|_| Vector::zeros());
            if rule.votes() {
                // Decided by the vote after the traversal.
                return (i, false);
            }
            let wanted = if comp.score <= FLAT * comp.extent {
                Vector::ith(n.iamax(), 1.0)
            } else {
                points[i].coords - origin - comp.sum / comp.count as f64
            };
            (i, n.dot(&wanted) < 0.0)
        })
        .collect()
}

/// Union–find with path halving and union by size.
struct DisjointSets {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let grandparent = self.parent[self.parent[x] as usize];
            self.parent[x] = grandparent;
            x = grandparent as usize;
        }
        x
    }

    /// Joins the sets of `a` and `b`; false if they were already one.
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return false;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b] = a as u32;
        self.size[a] += self.size[b];
        true
    }
}
