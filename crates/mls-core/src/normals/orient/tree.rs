//! The traversal that orients: Kruskal's minimum spanning forest of the neighbour graph
//! (edge keys sorted in parallel, union–find), a seed per component, and a depth-first walk
//! that carries the sign along the tree, cut into patches at creases for the voting rules.

use rayon::prelude::*;

use super::{Rule, is_canonical};
use crate::math::{Point, Vector, bounding_box_centre};
use crate::normals::{NeighbourGraph, NormalEstimate};
use crate::par::Parallelism;
use crate::status::PointStatus;

/// Kruskal's minimum spanning forest, then a traversal of each tree from its seed.
/// Returns (components, patches, flipped).
pub(super) fn orient_along_tree(
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
