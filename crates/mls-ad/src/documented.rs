//! The documented defaults and thresholds the witnesses depend on, restated from the documents
//! that state them and never imported from mls-core.
//!
//! A witness that took its configuration from mls-core would change with it: a changed default
//! (the jet's confidence 3 → 2, say) would move production and witness together and pass every
//! comparison. `cargo xtask validate` therefore runs production with mls-core's defaults (what
//! the command uses) and the witnesses with these values, and its "documented defaults" row
//! compares the two field by field. A default that changes must change here and in the
//! document cited beside it, in the same commit.

use mls_core::{JetConfig, NormalData};

/// The jet's highest total degree: "a weighted degree-4 polynomial height field" (README.md,
/// the methods; `docs/derivation.md`, "Fit": "a polynomial p of total degree 4").
pub const JET_DEGREE: usize = 4;
/// The jet's first support radius in h: "`ρ_j = 1.5 h · √2^j`" (`docs/derivation.md`,
/// "Scale"; README.md's example summary: "support 1.5h to 6.0h").
pub const JET_RADIUS: f64 = 1.5;
/// The jet's number of scales: "j = 0…4" (`docs/derivation.md`, "Scale"; 6.0h = 1.5h·√2⁴ in
/// README.md's example summary).
pub const JET_SCALES: usize = 5;
/// Whether the jet fits a lead scale `ρ_0/√2` with file normals (`docs/derivation.md`, "Lead
/// scale (file normals)").
pub const JET_LEAD: bool = true;
/// Γ, the half-width of the ladder's confidence intervals in predicted standard deviations:
/// "a scale is accepted while the intervals `k ± 3 sd` of all accepted scales intersect"
/// (`docs/derivation.md`, "Scale").
pub const JET_CONFIDENCE: f64 = 3.0;
/// Whether heights-only fits get the degree-2 candidates: "With heights only … every point
/// therefore also gets degree-2 candidates" (`docs/derivation.md`, "Degree (heights only)";
/// README.md's example summary: "or degree 2 on 3h to 8.5h chosen per point").
pub const JET_QUADRATIC: bool = true;
/// "a query where the anchors within reach all chose degree 2 on a support at least four
/// cells wide takes their blend" (`docs/derivation.md`, "Shared supports").
pub const JET_SHARE: bool = true;
/// The anchors' grid: "one sample per cell of side 1.5h" (`docs/derivation.md`, "Shared
/// supports"; so is every `SHARE_` value below).
pub const SHARE_CELL: f64 = 1.5;
/// "the anchors within 2 cells (3h) of the query".
pub const SHARE_REACH: f64 = 2.0;
/// "at least 3 anchors".
pub const SHARE_MIN_COUNT: usize = 3;
/// "a degree-2 fit on a support at least 4 cells (6h) wide".
pub const SHARE_MIN_SUPPORT: f64 = 4.0;
/// "each anchor's normal within about 25° of the blend's (cosine 0.9)".
pub const SHARE_MAX_TURN: f64 = 0.9;
/// "within 3 σ̂ of the nearest anchor's quadric".
pub const SHARE_RESIDUAL: f64 = 3.0;
/// The normal data of `JetConfig::default()`: the samples' normals fitted as slopes, the
/// role of measured (file) normals (`docs/derivation.md`, "Fit": "when the normals are
/// measured (file normals, `NormalData::Slopes`)"; README.md, `--normals`: "the jet fits file
/// normals as measured data"). The command sets it per run: slopes for file normals, heights
/// only for estimated ones.
pub const JET_NORMALS: NormalData = NormalData::Slopes;

/// The first degree-2 support, in h: "the supports `ρ = 3h·√2^j`, j = 0…3 (3 h to 8.5 h)"
/// (`docs/derivation.md`, "Degree (heights only)").
pub const QUADRATIC_RADIUS: f64 = 3.0;
/// The number of degree-2 supports (j = 0…3, same place).
pub const QUADRATIC_SCALES: usize = 4;
/// The most samples the largest degree-2 support may hold: "the largest of them holding at
/// most 2,048 samples" (same place).
pub const QUADRATIC_MAX_SAMPLES: usize = 2048;
/// Tukey's biweight cutoff, in robust standard deviations: "Tukey's cutoff of their residuals
/// (4.685 × 1.4826 × their median absolute residual)" (README.md, status code 8).
pub const BIWEIGHT_CUTOFF: f64 = 4.685;

/// The default ratio of h to the median local spacing: "`--h-factor F` | 2 | h = F × median
/// local spacing" (README.md, options; `docs/defaults.md`, "`--h-factor 2`").
pub const H_FACTOR: f64 = 2.0;
/// Neighbours of the local spacing behind the default h: "RMS distance to 12 neighbours"
/// (README.md, `--h-factor`; "Scan lines far apart": "the spacing behind the default h from
/// 12").
pub const SPACING_NEIGHBOURS: usize = 12;
/// Neighbours of normal estimation and of the orientation graph: "Estimated normals come from
/// each point's 16 nearest neighbours" (README.md, "Scan lines far apart"; the summary's
/// "estimated (weighted covariance, 16 neighbours)").
pub const NORMAL_NEIGHBOURS: usize = 16;
/// The kernel's default cutoff, in h: "`--cutoff C` | 5 | kernel truncated at C·h" (README.md,
/// options).
pub const CUTOFF: f64 = 5.0;
/// Fewest samples in the support for a curvature: "too_few_neighbours | fewer than 3 samples
/// within the support" (README.md, status codes).
pub const MIN_NEIGHBOURS: usize = 3;

/// The role of estimated normals in the jet: the frame only, heights fitted alone (README.md's
/// example summary: "normals give the frame only"; `docs/accuracy.md`: "estimated normals give
/// the frame only, as the CLI does"). File normals are slopes ([`JET_NORMALS`]).
pub const ESTIMATED_NORMALS: NormalData = NormalData::Ignore;
/// The eigenvalue gap below which an estimated normal is undefined, relative to the largest
/// eigenvalue: "λ1 − λ0 ≤ 1e-6 λ2" (README.md, status code 7).
pub const DEGENERACY_TOLERANCE: f64 = 1e-6;
/// The least share of neighbour pairs whose normals agree in sign before the command warns,
/// for file normals and for estimated ones: "when fewer than 99 % of neighbouring pairs agree
/// in sign … a warning says so" (README.md, `--normals`; "Estimated normals whose oriented
/// neighbour pairs agree in sign below 99 %"; `docs/orientation.md`: "warn below 99 %").
pub const MIN_CONSISTENCY: f64 = 0.99;

/// The adaptive ladder's number of scales: "h per point, from the chosen h up to 4× it"
/// (README.md, `--adaptive`), on the √2 ladder of `docs/derivation.md` (√2⁴ = 4: five scales).
pub const ADAPTIVE_SCALES: usize = 5;
/// Γ of the adaptive ladder: "intersecting the confidence intervals `k_j ± 2 sd_j`"
/// (`docs/derivation.md`, "Shrinkage, and the adaptive scale").
pub const ADAPTIVE_CONFIDENCE: f64 = 2.0;
/// The adaptive ladder's smallest scale in local spacings, the default h factor: "scales of at
/// least 2 local spacings" (`mls_core::AdaptiveConfig::new`'s documentation).
pub const ADAPTIVE_MIN_H_FACTOR: f64 = H_FACTOR;

/// The jet's configuration as documented, with the normal data `normals` (the command's
/// choice per run), every field written out so that a field added to `JetConfig` must be
/// restated here too.
pub fn jet_config(normals: NormalData) -> JetConfig {
    JetConfig {
        degree: JET_DEGREE,
        radius: JET_RADIUS,
        scales: JET_SCALES,
        lead: JET_LEAD,
        confidence: JET_CONFIDENCE,
        normals,
        quadratic: JET_QUADRATIC,
        share: JET_SHARE,
    }
}
