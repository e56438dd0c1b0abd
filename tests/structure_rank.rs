//! Within `single-branch`: the Hammerstein, Wiener and Wiener–Hammerstein fits ranked by
//! validation error put the true class first on simulated multisine records.

mod structure_common;

use hammerstein::structure::rank_single_branch;
use rand::{SeedableRng, rngs::StdRng};
use structure_common::{Family, Plant, battery_design, replay};

/// Random second-order Hammerstein and Wiener plants (random poles, zeros, polynomial
/// nonlinearity), the battery's design at 40 dB, several seeds each: the rate at which the true
/// class ranks first, and at which it ranks first decisively.
fn rates(seeds: std::ops::Range<u64>) -> Vec<(Family, usize, usize, usize)> {
    let mut out = Vec::new();
    for family in [Family::Hammerstein, Family::Wiener] {
        let (mut first, mut decisive, mut runs) = (0, 0, 0);
        for seed in seeds.clone() {
            let design = battery_design(100 + seed).generate().unwrap();
            let mut rng = StdRng::seed_from_u64(seed * 31 + family as u64);
            let plant = Plant::random(family, &mut rng, 1.0, 1.0);
            let Some(rec) = replay(&design, &plant, 40.0, seed + 7) else {
                continue;
            };
            let r = rank_single_branch(&rec, 2).unwrap();
            runs += 1;
            let want = match family {
                Family::Hammerstein => "hammerstein",
                _ => "wiener",
            };
            let top = &r.candidates[0];
            eprintln!(
                "{family:?} seed {seed}: {} first (decisive {}), MSEs {:?}",
                top.name,
                r.decisive,
                r.candidates
                    .iter()
                    .map(|c| (c.name.as_str(), c.validation_mse, c.dm_vs_best))
                    .collect::<Vec<_>>()
            );
            if top.name == want {
                first += 1;
                if r.decisive {
                    decisive += 1;
                }
            }
        }
        eprintln!("{family:?}: true class first in {first}/{runs}, decisively {decisive}/{runs}");
        out.push((family, first, decisive, runs));
    }
    out
}

#[test]
fn the_true_class_ranks_first() {
    // measured: 8/8 per class first (all decisive) over seeds 0..8
    for (family, first, _, runs) in rates(0..8) {
        assert_eq!(runs, 8);
        assert!(first >= 7, "{family:?}: true class first in {first}/{runs}");
    }
}
