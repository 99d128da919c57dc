//! The paper's reference tables for teaching (SPEC §8 "Teaching"): the pastes it printed, the
//! overhang test that set the 45° limit, and its comparisons of materials and of ceramic printing
//! methods — as the paper gives them ("The Model of Ceramic Surface Image Based on 3D Printing
//! Technology", `reference/ceramic-surface-paper.txt`: Tables 1, 3, 5 and 6 and §3.3). Names the
//! paper's text garbles are given as meant: "Findan orange G" is Sudan orange G, "ganmen owder"
//! garnet powder, "Lmsorganic" inorganic; the unnamed laser row of Table 6 is powder bed fusion.

use bevy_egui::egui;

use crate::widgets::explain;

/// Where every table below comes from.
pub const CITATION: &str = "From the paper behind Clayloft: \"The Model of Ceramic Surface Image Based on 3D Printing Technology\" (research article; its Tables 1, 3, 5, 6 and §3.3).";

/// A table: its title as the paper numbers it, the column heads and the rows.
pub struct Table {
    pub title: &'static str,
    pub note: &'static str,
    pub heads: &'static [&'static str],
    pub rows: &'static [&'static [&'static str]],
}

/// The overhang test of §3.3: cones printed at three inclinations and two layer thicknesses.
pub const OVERHANG_TEST: Table = Table {
    title: "Overhang test (§3.3): why the limit is 45°",
    note: "Models printed leaning 45°, 50° and 55° from vertical. With thin layers all three held; with 1 mm layers only 45° kept its shape — so 45° is the largest safe lean, Clayloft's default printer.max_overhang_deg.",
    heads: &["Inclination", "Layer 0.25 mm", "Layer 1.0 mm"],
    rows: &[
        &["45°", "good, lean as designed", "as designed"],
        &["50°", "good, lean as designed", "upper half bulges outward"],
        &["55°", "good, lean as designed", "upper half collapses"],
    ],
};

/// Table 5: the ceramic slurry.
pub const CERAMIC_SLURRY: Table = Table {
    title: "Table 5: formulation of a ceramic slurry",
    note: "A silicon-nitride slurry for direct writing: water and alcohols carry the powder, a dispersant keeps it from clumping, a binder holds the printed shape.",
    heads: &["Material", "wt. %", "vol. %"],
    rows: &[
        &["Si3N4 powder", "56.0", "30.2"],
        &["Yttrium-aluminium-garnet powder", "6.2", "2.3"],
        &["Distilled water", "24.9", "42.8"],
        &["Ethylene glycol", "4.4", "6.8"],
        &["Dispersant (polyacrylic and carboxylic acid)", "0.2", "0.3"],
        &["Ethanol", "7.2", "15.7"],
        &["Inorganic binder", "0.7", "1.1"],
        &["Deflocculant", "0.4", "0.8"],
    ],
};

/// Table 1: the photosensitive resin paste.
pub const RESIN_PASTE: Table = Table {
    title: "Table 1: formulation of a photosensitive resin paste",
    note: "The paste of the paper's screw-extrusion study (mass fractions, %).",
    heads: &["Reagent", "Mass fraction"],
    rows: &[
        &["PEG", "30"],
        &["ACMO", "28"],
        &["PPTTA", "37.99"],
        &["TPO", "1"],
        &["HQ", "1"],
        &["Sudan orange G", "0.01"],
        &["BYK", "2"],
    ],
};

/// Table 3: printing materials compared.
pub const MATERIALS: Table = Table {
    title: "Table 3: 3D-printing materials compared",
    note: "The plastics clay printing is most often compared with.",
    heads: &["Material", "Advantages", "Shortcomings"],
    rows: &[
        &[
            "ABS plastic",
            "excellent mechanical properties and pull-out strength; supports come off easily",
            "large prints lift off the bed; the bed must be heated to 80–120 °C",
        ],
        &[
            "PLA plastic",
            "biodegradable; glossy prints; flows well and does not crack easily; no odour",
            "supports are hard to remove; low impact resistance",
        ],
    ],
};

/// Table 6: ceramic printing methods compared.
pub const METHODS: Table = Table {
    title: "Table 6: ceramic 3D-printing methods compared",
    note: "Extrusion (what Clayloft drives) is the cheapest and simplest; its price is resolution.",
    heads: &[
        "Technique",
        "Strategy",
        "Cost",
        "Time",
        "Advantages",
        "Disadvantages",
    ],
    rows: &[
        &[
            "Extrusion",
            "ceramic paste with polymer binder and plasticiser",
            "low–moderate",
            "slow",
            "straightforward; porous scaffolds or dense parts",
            "limited resolution",
        ],
        &[
            "Binder jetting",
            "ceramic powder bed and polymer binder",
            "moderate–high",
            "moderate/fast",
            "larger, porous parts; few sacrificial materials",
            "very dense ceramics are hard",
        ],
        &[
            "Material jetting",
            "ceramic-laden droplets on a substrate",
            "low–moderate",
            "slow/moderate",
            "small models; smooth surfaces",
            "large models are hard",
        ],
        &[
            "Powder bed fusion",
            "ceramic powder bed with a laser",
            "high",
            "fast",
            "porous scaffolds or dense parts",
            "distortion and warping, micro-cracks",
        ],
        &[
            "Vat photopolymerisation",
            "ceramic dispersed in photosensitive resin",
            "moderate",
            "moderate/fast",
            "precise; smooth surfaces",
            "much post-processing",
        ],
    ],
};

/// Every table, in the order the window shows them.
pub const TABLES: [&Table; 5] = [
    &OVERHANG_TEST,
    &CERAMIC_SLURRY,
    &RESIN_PASTE,
    &MATERIALS,
    &METHODS,
];

/// The window's contents: the citation, then each table under its own header.
pub fn reference(ui: &mut egui::Ui) {
    explain(ui, CITATION);
    for (k, t) in TABLES.iter().enumerate() {
        egui::CollapsingHeader::new(t.title)
            .default_open(k == 0)
            .show(ui, |ui| {
                explain(ui, t.note);
                egui::Grid::new(t.title).striped(true).show(ui, |ui| {
                    for h in t.heads {
                        ui.strong(*h);
                    }
                    ui.end_row();
                    for row in t.rows {
                        for cell in *row {
                            ui.add(egui::Label::new(*cell).wrap());
                        }
                        ui.end_row();
                    }
                });
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    #[test]
    fn the_tables_are_shown_with_their_source() {
        for t in TABLES {
            assert!(
                t.rows.iter().all(|r| r.len() == t.heads.len()),
                "{}",
                t.title
            );
        }
        let mut h = Harness::builder()
            .with_size(egui::vec2(700.0, 1600.0))
            .build_ui(reference);
        h.run();
        assert!(
            h.query_by_label_contains("The Model of Ceramic Surface Image")
                .is_some()
        );
        // The overhang test is open at first; the others open by their title.
        assert!(h.query_by_label("upper half collapses").is_some());
        assert!(h.query_by_label("Si3N4 powder").is_none());
        h.get_by_label("Table 5: formulation of a ceramic slurry")
            .click();
        h.run();
        assert!(h.query_by_label("Si3N4 powder").is_some());
        assert!(h.query_by_label("56.0").is_some());
    }
}
