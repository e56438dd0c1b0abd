//! The model file's JSON and the settings' serde: the settings block of committed model files
//! (written before the options had a struct of their own) saves byte for byte as it was written
//! (the rest of those files predates later report fields, and serde_json without its
//! `float_roundtrip` feature may change a float's last digit on a load), the settings block is flat (the [`FitOptions`] flattened), the
//! options round-trip through serde, and the model (de)serialises through its file format.

mod hammerstein_common;
use hammerstein::fit::{Feedthrough, FitOptions, HammersteinModel, Screening};
use hammerstein::regressors::{Effect, EffectSet, Udn};
use hammerstein::{Hammerstein, IoData, Order};
use hammerstein_common::*;

/// Model files written by `save` before the options had a struct of their own.
const SEEDS: [&str; 3] = ["lin", "udn", "poly"];

fn seed(name: &str) -> String {
    let path = format!(
        "{}/fuzz/seeds/model_file/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// The keys of the settings block, in the order the files have always had.
const SETTINGS_KEYS: [&str; 14] = [
    "effects",
    "method",
    "horizon",
    "order",
    "max_iter",
    "tolerance",
    "refine",
    "backend",
    "normalization",
    "with_d",
    "delay",
    "offset",
    "init",
    "seed",
];

/// The settings object's text in `text` (a pretty-printed model file).
fn settings_block(text: &str) -> &str {
    let start = text.find("\"settings\": {").expect("a settings block");
    let len = text[start..].find("\n  },").expect("the block's end");
    &text[start..start + len]
}

/// The keys of the settings object in `text` (a pretty-printed model file), in order.
fn settings_keys(text: &str) -> Vec<String> {
    let start = text.find("\"settings\": {").expect("a settings block");
    let mut keys = Vec::new();
    for line in text[start..].lines().skip(1) {
        if line.starts_with("  }") {
            break;
        }
        // the settings' own keys are indented by four spaces
        if let Some(rest) = line.strip_prefix("    \"")
            && let Some(end) = rest.find('"')
        {
            keys.push(rest[..end].to_string());
        }
    }
    keys
}

#[test]
fn committed_model_files_keep_their_settings_block() {
    for name in SEEDS {
        let text = seed(name);
        let model = HammersteinModel::from_json(&text).unwrap();
        let saved = serde_json::to_string_pretty(&model.to_file()).unwrap();
        assert_eq!(
            settings_block(&saved),
            settings_block(&text),
            "{name}.json's settings saved differently"
        );
        assert_eq!(settings_keys(&saved), SETTINGS_KEYS);
        // the model's own Serialize is the file format
        assert_eq!(serde_json::to_string_pretty(&model).unwrap(), saved);
        // and its Deserialize reads the file
        let back: HammersteinModel<f64> = serde_json::from_str(&text).unwrap();
        assert_eq!(back.settings().options(), model.settings().options());
        assert_eq!(
            settings_block(&serde_json::to_string_pretty(&back).unwrap()),
            settings_block(&text)
        );
    }
}

#[test]
fn settings_file_stays_flat_for_non_default_rules() {
    let sh = EffectSet::of(&[Effect::Hysteresis, Effect::Saturation]);
    let truth = Udn::<f64>::with_params(sh, &[2.0, 0.5, 1.5, -1.0]).unwrap();
    let data: IoData<f64> = record(&truth, &example1_input(600, 3), 0.0);
    let model = Hammerstein::udn(sh)
        .order(Order::Fixed(2))
        .feedthrough(Feedthrough::Present)
        .screening(Screening {
            threshold: 1_000_000,
            ..Screening::default()
        })
        .refine(false)
        .fit(&data)
        .unwrap();
    assert_eq!(model.settings().options().screening.threshold, 1_000_000);
    let text = serde_json::to_string_pretty(&model).unwrap();
    assert_eq!(settings_keys(&text), SETTINGS_KEYS);
    let loaded = HammersteinModel::from_json(&text).unwrap();
    let o = loaded.settings().options();
    assert_eq!(o.feedthrough(), Feedthrough::Present);
    assert!(o.screening.is_default());
    assert_eq!(o.order, Order::Fixed(2));
    assert!(!o.refine);
    // saved again: the same settings
    let again = serde_json::to_string_pretty(&loaded).unwrap();
    assert_eq!(settings_block(&again), settings_block(&text));
}

#[test]
fn fit_options_round_trip_through_serde() {
    let default = FitOptions::default();
    let text = serde_json::to_string(&default).unwrap();
    assert!(text.contains("\"d_auto\":true"), "{text}");
    assert!(!text.contains("screening"), "{text}");
    assert_eq!(serde_json::from_str::<FitOptions>(&text).unwrap(), default);

    let settings = Hammerstein::<f64>::sh()
        .horizon(11)
        .with_d(true)
        .delay(2)
        .screening(Screening::off());
    let o = settings.options().clone();
    assert_eq!(
        (o.horizon, o.delay, o.with_d, o.d_auto),
        (11, 2, true, false)
    );
    let text = serde_json::to_string(&o).unwrap();
    assert!(!text.contains("d_auto"), "{text}");
    assert!(text.contains("screening"), "{text}");
    let back: FitOptions = serde_json::from_str(&text).unwrap();
    assert_eq!(back, o);
    // the options applied to other settings: the same plain data, their own nonlinearity
    let applied = Hammerstein::<f64>::linear().with_options(back);
    assert_eq!(applied.options(), settings.options());
    assert_eq!(applied.effects(), Some(EffectSet::empty()));
}

#[test]
fn debug_shows_the_options_and_the_trait_objects_by_name() {
    let s = Hammerstein::<f64>::sh().horizon(9);
    let text = format!("{s:?}");
    assert!(text.contains("nonlinearity: \"udn["), "{text}");
    assert!(text.contains("horizon: 9"), "{text}");
    assert!(text.contains("output_map: None"), "{text}");
}

/// A model file gives back every number bit for bit: JSON's shortest decimal of a double is
/// parsed to the same double (serde_json's `float_roundtrip`; without it 0.39469780717138203,
/// a fitted B entry, came back one ulp off and a reloaded model simulated differently).
#[test]
fn model_files_give_back_every_double_bit_for_bit() {
    let mut xs = vec![
        0.39469780717138203,
        0.0014897362400291903,
        -19455.503114954558,
    ];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..20_000 {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = f64::from_bits(state >> 2);
        if x.is_finite() {
            xs.push(x);
            xs.push(-x * 1e-3);
        }
    }
    for x in xs {
        let text = serde_json::to_string(&x).unwrap();
        let back: f64 = serde_json::from_str(&text).unwrap();
        assert_eq!(
            back.to_bits(),
            x.to_bits(),
            "{x:e} written as {text} read as {back:e}"
        );
    }
}
