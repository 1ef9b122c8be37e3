//! The "documented defaults" row of `cargo xtask validate`: every default and threshold that
//! a witness restates (`mls_ad::documented`, from README.md and `docs/`) against the value in
//! mls-core that the command runs with. The witnesses run with the restated values and
//! production with its own, so a changed default also moves the rows that depend on it; this
//! row names the field and both values.

use mls_ad::documented as doc;
use mls_core::adaptive::AdaptiveConfig;
use mls_core::normals::{
    DEFAULT_DEGENERACY_TOLERANCE, DEFAULT_H_FACTOR, DEFAULT_NEIGHBOURS, DEFAULT_SPACING_NEIGHBOURS,
    NormalsConfig, Orientation,
};
use mls_core::{Cutoff, JetConfig, MlsConfig, NormalData};

use crate::validate::{Q, Tally};

/// One default: where it lives in mls-core, its value there and as documented, and where it
/// is documented.
pub(crate) struct Documented {
    pub field: &'static str,
    pub production: String,
    pub documented: String,
    pub source: &'static str,
}

impl Documented {
    pub fn agrees(&self) -> bool {
        self.production == self.documented
    }
}

fn field(
    field: &'static str,
    production: impl std::fmt::Debug,
    documented: impl std::fmt::Debug,
    source: &'static str,
) -> Documented {
    Documented {
        field,
        production: format!("{production:?}"),
        documented: format!("{documented:?}"),
        source,
    }
}

fn radius(c: Cutoff) -> Option<f64> {
    match c {
        Cutoff::Radius(r) => Some(r),
        Cutoff::None => None,
    }
}

/// Every default a witness restates, with mls-core's value and the documented one.
pub(crate) fn defaults() -> Vec<Documented> {
    let jet = JetConfig::default();
    let normals = NormalsConfig::default();
    let mls = MlsConfig::new(1.0);
    let adaptive = AdaptiveConfig::new(1.0);
    const DERIVATION_SCALE: &str = "docs/derivation.md, the jet's \"Scale\"";
    const DERIVATION_QUADRATIC: &str = "docs/derivation.md, the jet's \"Degree (heights only)\"";
    const DERIVATION_SHARE: &str = "docs/derivation.md, the jet's \"Shared supports\"";
    vec![
        field(
            "JetConfig::default().degree",
            jet.degree,
            doc::JET_DEGREE,
            "README.md (methods), docs/derivation.md \"Fit\"",
        ),
        field(
            "JetConfig::default().radius",
            jet.radius,
            doc::JET_RADIUS,
            DERIVATION_SCALE,
        ),
        field(
            "JetConfig::default().scales",
            jet.scales,
            doc::JET_SCALES,
            DERIVATION_SCALE,
        ),
        field(
            "JetConfig::default().lead",
            jet.lead,
            doc::JET_LEAD,
            "docs/derivation.md, \"Lead scale (file normals)\"",
        ),
        field(
            "JetConfig::default().confidence",
            jet.confidence,
            doc::JET_CONFIDENCE,
            DERIVATION_SCALE,
        ),
        field(
            "JetConfig::default().normals",
            jet.normals == NormalData::Slopes,
            doc::JET_NORMALS == NormalData::Slopes,
            "docs/derivation.md \"Fit\", README.md --normals (file normals as slopes)",
        ),
        field(
            "JetConfig::default().quadratic",
            jet.quadratic,
            doc::JET_QUADRATIC,
            DERIVATION_QUADRATIC,
        ),
        field(
            "jet::QUADRATIC_RADIUS",
            mls_core::jet::QUADRATIC_RADIUS,
            doc::QUADRATIC_RADIUS,
            DERIVATION_QUADRATIC,
        ),
        field(
            "jet::QUADRATIC_SCALES",
            mls_core::jet::QUADRATIC_SCALES,
            doc::QUADRATIC_SCALES,
            DERIVATION_QUADRATIC,
        ),
        field(
            "jet::QUADRATIC_MAX_SAMPLES",
            mls_core::jet::QUADRATIC_MAX_SAMPLES,
            doc::QUADRATIC_MAX_SAMPLES,
            DERIVATION_QUADRATIC,
        ),
        field(
            "JetConfig::default().share",
            jet.share,
            doc::JET_SHARE,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_CELL",
            mls_core::jet::ANCHOR_CELL,
            doc::SHARE_CELL,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_REACH",
            mls_core::jet::ANCHOR_REACH,
            doc::SHARE_REACH,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_MIN_COUNT",
            mls_core::jet::ANCHOR_MIN_COUNT,
            doc::SHARE_MIN_COUNT,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_MIN_SUPPORT",
            mls_core::jet::ANCHOR_MIN_SUPPORT,
            doc::SHARE_MIN_SUPPORT,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_MAX_TURN",
            mls_core::jet::ANCHOR_MAX_TURN,
            doc::SHARE_MAX_TURN,
            DERIVATION_SHARE,
        ),
        field(
            "jet::ANCHOR_RESIDUAL",
            mls_core::jet::ANCHOR_RESIDUAL,
            doc::SHARE_RESIDUAL,
            DERIVATION_SHARE,
        ),
        field(
            "jet::BIWEIGHT_CUTOFF",
            mls_core::jet::BIWEIGHT_CUTOFF,
            doc::BIWEIGHT_CUTOFF,
            "README.md, status code 8",
        ),
        field(
            "normals::DEFAULT_H_FACTOR",
            DEFAULT_H_FACTOR,
            doc::H_FACTOR,
            "README.md --h-factor, docs/defaults.md",
        ),
        field(
            "normals::DEFAULT_SPACING_NEIGHBOURS",
            DEFAULT_SPACING_NEIGHBOURS,
            doc::SPACING_NEIGHBOURS,
            "README.md --h-factor, \"Scan lines far apart\"",
        ),
        field(
            "normals::DEFAULT_NEIGHBOURS",
            DEFAULT_NEIGHBOURS,
            doc::NORMAL_NEIGHBOURS,
            "README.md, \"Scan lines far apart\"",
        ),
        field(
            "NormalsConfig::default().k",
            normals.k,
            doc::NORMAL_NEIGHBOURS,
            "README.md, \"Scan lines far apart\"",
        ),
        field(
            "normals::DEFAULT_DEGENERACY_TOLERANCE",
            DEFAULT_DEGENERACY_TOLERANCE,
            doc::DEGENERACY_TOLERANCE,
            "README.md, status code 7",
        ),
        field(
            "NormalsConfig::default().degeneracy_tolerance",
            normals.degeneracy_tolerance,
            doc::DEGENERACY_TOLERANCE,
            "README.md, status code 7",
        ),
        field(
            "pipeline::MIN_FILE_CONSISTENCY",
            mls_pipeline::pipeline::MIN_FILE_CONSISTENCY,
            doc::MIN_CONSISTENCY,
            "README.md --normals, docs/orientation.md \"Normals from a file\"",
        ),
        field(
            "pipeline::MIN_ESTIMATED_CONSISTENCY",
            mls_pipeline::pipeline::MIN_ESTIMATED_CONSISTENCY,
            doc::MIN_CONSISTENCY,
            "README.md (estimated normals below 99 %), docs/orientation.md",
        ),
        field(
            "NormalsConfig::default().orientation is outward",
            normals.orientation == Orientation::Outward,
            true,
            "README.md --orient (mst: outward)",
        ),
        field(
            "Cutoff::DEFAULT",
            radius(Cutoff::DEFAULT),
            Some(doc::CUTOFF),
            "README.md --cutoff",
        ),
        field(
            "MlsConfig::new(h).cutoff",
            radius(mls.cutoff),
            Some(doc::CUTOFF),
            "README.md --cutoff",
        ),
        field(
            "mls_pipeline::DEFAULT_CUTOFF (--cutoff's default on the command line)",
            mls_pipeline::parse_cutoff(mls_pipeline::DEFAULT_CUTOFF)
                .ok()
                .and_then(radius),
            Some(doc::CUTOFF),
            "README.md --cutoff",
        ),
        field(
            "MlsConfig::new(h).min_neighbours",
            mls.min_neighbours,
            doc::MIN_NEIGHBOURS,
            "README.md, status code 2",
        ),
        field(
            "AdaptiveConfig::new(h).scales",
            adaptive.scales,
            doc::ADAPTIVE_SCALES,
            "README.md --adaptive (h up to 4×)",
        ),
        field(
            "AdaptiveConfig::new(h).confidence",
            adaptive.confidence,
            doc::ADAPTIVE_CONFIDENCE,
            "docs/derivation.md, \"Shrinkage, and the adaptive scale\"",
        ),
        field(
            "AdaptiveConfig::new(h).min_h_factor",
            adaptive.min_h_factor,
            doc::ADAPTIVE_MIN_H_FACTOR,
            "AdaptiveConfig::new's documentation",
        ),
        field(
            "AdaptiveConfig::new(h).surface.cutoff",
            radius(adaptive.surface.cutoff),
            Some(doc::CUTOFF),
            "README.md --cutoff",
        ),
    ]
}

/// Records the row (1 per default that differs from its documented value) and returns the
/// report's table and a failure message per difference.
pub(crate) fn check(tally: &mut Tally) -> (String, Vec<String>) {
    let mut table = String::from(
        "\nDocumented defaults (the witnesses' values, `mls_ad::documented`) against mls-core's:\n\n\
         | default | mls-core | documented | documented in |\n| --- | --- | --- | --- |\n",
    );
    let mut failures = Vec::new();
    for d in defaults() {
        tally.record(Q::Defaults, f64::from(!d.agrees()), 0);
        table.push_str(&format!(
            "| `{}` | {} | {} | {} |\n",
            d.field, d.production, d.documented, d.source
        ));
        if !d.agrees() {
            failures.push(format!(
                "documented defaults: {} is {} in mls-core but {} as documented in {} \
                 (change the document and mls_ad::documented with it)",
                d.field, d.production, d.documented, d.source
            ));
        }
    }
    (table, failures)
}
