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
    /// Towards a viewpoint (the scanner position): the seed of each component is its point
    /// closest to the viewpoint `v`, whose normal gets `n · (v − p) ≥ 0`. On a smooth surface
    /// the closest point is visible and its normal is parallel to the line of sight, so the
    /// seed's sign is unambiguous.
    Viewpoint(Point),
}

/// What [`orient_normals`] did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrientationReport {
    /// Points with an estimated normal (the nodes of the orientation graph).
    pub oriented: usize,
    /// Connected components of the graph among those points, each seeded on its own; 0 for
    /// [`Orientation::None`], which builds no tree.
    pub components: usize,
    /// Normals whose sign was changed.
    pub flipped: usize,
    /// [`orientation_consistency`] after orientation; `None` when no edge joins two points
    /// with normals.
    pub consistency: Option<f64>,
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
/// sharp bends last (Hoppe et al. 1992). Each connected component is seeded by `orientation`;
/// from the seed, a child's normal is flipped when `n_child · n_parent < 0`.
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
    check_points(points)?;
    let k = graph.k();
    // Edges are numbered `i·k + slot` in 32 bits so that a sort key is one u64.
    let edge_ids = n.saturating_mul(k);
    if edge_ids > 1 << 32 {
        return Err(NormalsError::GraphTooLarge(edge_ids));
    }
    let oriented = estimates.iter().filter(|e| e.is_ok()).count();
    let (components, flipped) = match orientation {
        Orientation::None => (0, 0),
        _ => orient_along_tree(points, graph, estimates, orientation, par),
    };
    let consistency = consistency_of(graph, par, |i| {
        estimates
            .get(i)
            .and_then(|e| e.as_ref().ok())
            .map(|e| e.normal.into_inner())
    });
    Ok(OrientationReport {
        oriented,
        components,
        flipped,
        consistency,
    })
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
    let (all, agree) = match par {
        Parallelism::Sequential => (0..graph.len()).map(count).fold((0, 0), add),
        Parallelism::Rayon => (0..graph.len())
            .into_par_iter()
            .with_min_len(1024)
            .map(count)
            .reduce(|| (0, 0), add),
    };
    (all > 0).then(|| agree as f64 / all as f64)
}

/// Kruskal's minimum spanning forest, then a traversal of each tree from its seed.
/// Returns (components, flipped).
fn orient_along_tree(
    points: &[Point],
    graph: &NeighbourGraph,
    estimates: &mut [Result<NormalEstimate, PointStatus>],
    orientation: Orientation,
    par: Parallelism,
) -> (usize, usize) {
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
    match par {
        Parallelism::Sequential => keys.sort_unstable(),
        Parallelism::Rayon => keys.par_sort_unstable(),
    }

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

    let seeds = choose_seeds(points, est, &mut sets, orientation);
    let components = seeds.len();

    let mut flipped = 0;
    let mut visited = vec![false; n];
    let mut stack: Vec<u32> = Vec::new();
    for (seed, flip_seed) in seeds {
        if flip_seed {
            flip(&mut estimates[seed]);
            flipped += 1;
        }
        visited[seed] = true;
        stack.push(seed as u32);
        // A node's sign is final when it is discovered, so depth-first order is as good as
        // breadth-first and needs no queue.
        while let Some(u) = stack.pop() {
            let u = u as usize;
            let Some(nu) = normal(estimates, u) else {
                continue;
            };
            for &w in &adjacent[offsets[u]..offsets[u + 1]] {
                let w = w as usize;
                if visited[w] {
                    continue;
                }
                visited[w] = true;
                if normal(estimates, w).is_some_and(|nw| nw.dot(&nu) < 0.0) {
                    flip(&mut estimates[w]);
                    flipped += 1;
                }
                stack.push(w as u32);
            }
        }
    }
    (components, flipped)
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
    let counts: Vec<usize> = match par {
        Parallelism::Sequential => (0..blocks).map(count).collect(),
        Parallelism::Rayon => (0..blocks).into_par_iter().map(count).collect(),
    };
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
    orientation: Orientation,
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
        let score = match orientation {
            Orientation::Viewpoint(v) => -(v - points[i]).norm_squared(),
            _ => {
                let centroid = comp.sum / comp.count as f64;
                let r = points[i].coords - origin - centroid;
                comp.extent = comp.extent.max(r.norm());
                e.normal.as_vector().dot(&r).abs() * e.confidence()
            }
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
            let wanted = match orientation {
                Orientation::Viewpoint(v) => v - points[i],
                _ if comp.score <= FLAT * comp.extent => {
                    let axis = n.iamax();
                    Vector::ith(axis, 1.0)
                }
                _ => points[i].coords - origin - comp.sum / comp.count as f64,
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
