//! Unit tests of the tile plan: the reach of each estimator, the grid's box sums, the plan's
//! split and its refusals.

use super::*;

/// The reach of each estimator, with the millionth's margin: the kernel's support, the
/// jet's largest radius (6 h by default; 8.5 h with heights only, the degree-2 candidates',
/// and 3 h more for the blend of shared supports), and 3 h more for estimated normals.
#[test]
fn reach_is_the_support_of_what_decides_a_point() {
    let h = 0.5;
    let margin = 1.0 + 1e-6;
    assert_eq!(
        reach(h, Cutoff::Radius(5.0), None, false),
        Some(5.0 * h * margin)
    );
    assert_eq!(
        reach(h, Cutoff::Radius(5.0), None, true),
        Some((5.0 * h + NORMALS_REACH * h) * margin)
    );
    let jet = JetConfig::default();
    assert_eq!(
        reach(h, Cutoff::Radius(5.0), Some(&jet), false),
        Some(jet.max_radius() * h * margin)
    );
    // Heights only: the degree-2 candidates' largest support, 3h·√2³ ≈ 8.49 h, and the
    // blend's reach of 2 cells of 1.5 h (its anchors' supports).
    let heights = JetConfig {
        normals: crate::NormalData::Ignore,
        share: false,
        ..JetConfig::default()
    };
    assert_eq!(
        reach(h, Cutoff::Radius(5.0), Some(&heights), true),
        Some((3.0 * 2f64.sqrt().powi(3) * h + NORMALS_REACH * h) * margin)
    );
    let shared = JetConfig {
        share: true,
        ..heights
    };
    assert_eq!(
        reach(h, Cutoff::Radius(5.0), Some(&shared), true),
        Some(((3.0 * 2f64.sqrt().powi(3) + 3.0) * h + NORMALS_REACH * h) * margin)
    );
    assert_eq!(reach(h, Cutoff::None, None, true), None);
}

/// A flat 10 × 5 box in at most 50 cells: unit cells, 10 × 5 × 1 of them.
#[test]
fn a_grid_of_unit_cells_over_a_flat_box() {
    let grid = Grid::new(Vector::zeros(), Vector::new(10.0, 5.0, 0.0), 50).unwrap();
    assert_eq!(grid.cell(), 1.0);
    assert_eq!(grid.dims(), [10, 5, 1]);
    assert_eq!((grid.len(), grid.is_empty()), (50, false));
    // Cells by floor, points outside the box in the nearest cell.
    for (p, cell) in [
        ((0.5, 0.5), [0, 0, 0]),
        ((3.7, 4.2), [3, 4, 0]),
        ((-5.0, 2.5), [0, 2, 0]),
        ((100.0, 100.0), [9, 4, 0]),
    ] {
        assert_eq!(grid.cell_of(&Point::new(p.0, p.1, 0.0)), cell, "{p:?}");
    }
}

/// A 20 × 10 box from (2, −1) in at most 50 cells: cells of 2. A block of cells has its
/// inner bounds on the grid lines and is open where it meets the grid's edge, since the
/// points beyond the box belong to the outer cells.
#[test]
fn a_block_of_cells_spans_its_grid_lines_and_is_open_at_the_grid_edge() {
    let grid = Grid::new(Vector::new(2.0, -1.0, 0.0), Vector::new(22.0, 9.0, 0.0), 50).unwrap();
    assert_eq!((grid.cell(), grid.dims()), (2.0, [10, 5, 1]));
    assert_eq!(grid.cell_of(&Point::new(7.9, 2.9, 0.0)), [2, 1, 0]);
    let inf = f64::INFINITY;
    assert_eq!(
        grid.world_box([3, 1, 0], [7, 4, 1]),
        ([8.0, 1.0, -inf], [16.0, 7.0, inf])
    );
    assert_eq!(
        grid.world_box([0, 2, 0], [10, 5, 1]),
        ([-inf, 3.0, -inf], [inf, inf, inf])
    );
}

/// A point loads exactly the tiles within its reach: those whose box (open at the grid's
/// edge) lies within `reach` of it, found here by brute force over every tile.
#[test]
fn a_point_loads_exactly_the_tiles_within_its_reach() {
    let mut points = sheet();
    let reach = 0.35;
    let plan = plan_of(&points, 1 << 12, reach, 5_000);
    assert_eq!(plan.reach(), reach);
    // Beyond the box too, where the outer cells hold the points.
    points.extend([Point::new(-3.0, 5.0, 0.0), Point::new(30.0, 30.0, 9.0)]);
    let g = plan.grid();
    let bound = |c: usize, i: usize, edge: f64| {
        if c == 0 || c == g.dims()[i] {
            edge
        } else {
            g.lo[i] + c as f64 * g.cell()
        }
    };
    for p in points.iter().step_by(13) {
        let mut near = Vec::new();
        plan.tiles_near(p, |t| near.push(t));
        near.sort_unstable();
        let want: Vec<usize> = (0..plan.tiles().len())
            .filter(|&t| {
                let tile = &plan.tiles()[t];
                let d2: f64 = (0..3)
                    .map(|i| {
                        let lo = bound(tile.start[i], i, f64::NEG_INFINITY);
                        let hi = bound(tile.end[i], i, f64::INFINITY);
                        (lo - p[i]).max(p[i] - hi).max(0.0).powi(2)
                    })
                    .sum();
                d2 <= reach * reach
            })
            .collect();
        assert_eq!(near, want, "{p}");
    }
}

/// A row of unit cells without halo (reach 0), split until each tile holds at most 40
/// points: the plane is at the median of the points, not of the cells, and a box of two
/// cells can still be split.
#[test]
fn a_box_is_split_at_the_median_of_its_points() {
    let tiles_of = |counts: &[u64], capacity: u64| -> Vec<([usize; 3], [usize; 3], u64)> {
        let n = counts.len();
        let grid = Grid::new(Vector::zeros(), Vector::new(n as f64, 0.0, 0.0), n).unwrap();
        assert_eq!(grid.dims(), [n, 1, 1]);
        let plan = TilePlan::new(grid, counts, 0.0, capacity).unwrap();
        plan.tiles()
            .iter()
            .map(|t| {
                assert_eq!(t.loaded, t.points);
                (t.start, t.end, t.points)
            })
            .collect()
    };
    // 80 points, half of them in the first cell: one plane, after that cell.
    assert_eq!(
        tiles_of(&[40, 0, 0, 0, 10, 10, 10, 10], 40),
        [([0, 0, 0], [1, 1, 1], 40), ([1, 0, 0], [8, 1, 1], 40)]
    );
    // The first plane holding half the points, not the last: the empty cells go right.
    assert_eq!(
        tiles_of(&[10, 10, 10, 10, 0, 0, 0, 40], 40),
        [([0, 0, 0], [4, 1, 1], 40), ([4, 0, 0], [8, 1, 1], 40)]
    );
    assert_eq!(
        tiles_of(&[20, 20], 20),
        [([0, 0, 0], [1, 1, 1], 20), ([1, 0, 0], [2, 1, 1], 20)]
    );
}

fn plan_of(points: &[Point], max_cells: usize, reach: f64, capacity: u64) -> TilePlan {
    let (lo, hi) = points.iter().fold(
        (
            Vector::repeat(f64::INFINITY),
            Vector::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(&p.coords), hi.sup(&p.coords)),
    );
    let grid = Grid::new(lo, hi, max_cells).unwrap();
    let mut counts = vec![0u64; grid.len()];
    for p in points {
        counts[grid.index_of(p)] += 1;
    }
    TilePlan::new(grid, &counts, reach, capacity).unwrap()
}

/// A jittered 200 × 200 grid on a wavy sheet.
fn sheet() -> Vec<Point> {
    (0..40_000)
        .map(|i| {
            let (x, y) = ((i % 200) as f64 * 0.1, (i / 200) as f64 * 0.1);
            let j = ((i * 7919) % 97) as f64 / 97.0 * 0.03;
            Point::new(x + j, y - j, (x * 0.3).sin() + 0.2 * y)
        })
        .collect()
}

#[test]
fn tiles_cover_every_point_once_within_capacity() {
    let points = sheet();
    let reach = 0.35;
    let plan = plan_of(&points, 1 << 16, reach, 4_000);
    assert!(plan.tiles().len() >= 16, "{} tiles", plan.tiles().len());
    let mut core = vec![0u64; plan.tiles().len()];
    let mut loaded = vec![0u64; plan.tiles().len()];
    for p in &points {
        core[plan.tile_of(p)] += 1;
        plan.tiles_near(p, |t| loaded[t] += 1);
    }
    for (t, tile) in plan.tiles().iter().enumerate() {
        assert_eq!(core[t], tile.points);
        assert!(
            loaded[t] <= tile.loaded && tile.loaded <= 4_000,
            "{t}: {tile:?}"
        );
    }
    assert_eq!(core.iter().sum::<u64>(), points.len() as u64);
}

/// Every sample within the reach of a core point is loaded by that point's tile: the
/// property that makes a tile's results the whole run's.
#[test]
fn halo_holds_every_neighbour_within_reach() {
    let points = sheet();
    let reach = 0.35;
    let plan = plan_of(&points, 1 << 12, reach, 5_000);
    let mut loads: Vec<Vec<usize>> = vec![Vec::new(); points.len()];
    for (i, p) in points.iter().enumerate() {
        plan.tiles_near(p, |t| loads[i].push(t));
    }
    for (i, p) in points.iter().enumerate().step_by(37) {
        let t = plan.tile_of(p);
        for (j, q) in points.iter().enumerate() {
            if (p - q).norm() <= reach / (1.0 + 1e-6) {
                assert!(loads[j].contains(&t), "{j} near {i} is not in tile {t}");
            }
        }
    }
}

#[test]
fn one_tile_when_everything_fits() {
    let points = sheet();
    let plan = plan_of(&points, 1 << 10, 0.35, 40_000);
    assert_eq!(plan.tiles().len(), 1);
    assert_eq!(plan.tiles()[0].points, 40_000);
}

#[test]
fn a_budget_below_one_neighbourhood_is_an_error() {
    let points = sheet();
    let (lo, hi) = (Vector::new(-1.0, -1.0, -2.0), Vector::new(21.0, 21.0, 8.0));
    let grid = Grid::new(lo, hi, 1 << 12).unwrap();
    let mut counts = vec![0u64; grid.len()];
    for p in &points {
        counts[grid.index_of(p)] += 1;
    }
    let err = TilePlan::new(grid, &counts, 3.0, 100).unwrap_err();
    assert!(matches!(err, TilingError::TooDense { .. }), "{err}");
}

#[test]
fn grid_respects_its_cell_budget_on_flat_and_degenerate_boxes() {
    let g = Grid::new(Vector::zeros(), Vector::new(1000.0, 10.0, 0.0), 1 << 20).unwrap();
    assert!(g.len() <= 1 << 20 && g.len() > 1 << 18, "{:?}", g.dims());
    let one = Grid::new(Vector::repeat(5.0), Vector::repeat(5.0), 100).unwrap();
    assert_eq!(one.len(), 1);
    assert!(Grid::new(Vector::zeros(), Vector::new(f64::NAN, 1.0, 1.0), 10).is_err());
}
