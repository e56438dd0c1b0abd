//! The typed size estimates a diagnosis quotes: what is measured ([`Quantity`]), where it was
//! read ([`Source`]: the residual or the refitted model), its value and standard error
//! ([`Estimate`]), and the collection a candidate's evidence, refit and suggestion carry
//! ([`Estimates`]). Each estimate prints and serialises under the name the command line and its
//! JSON show ("residual_half_width", "a", "order", "output.c2", …); a collection serialises as
//! the map name → value.

use crate::fit::HammersteinModel;
use crate::real::Real;
use serde::ser::{SerializeMap, SerializeStruct};
use serde::{Serialize, Serializer};
use std::borrow::Cow;

/// Prefix of the output map's parameters in a refit's estimates ("output.c2", "output.lower").
pub const OUTPUT_MAP_PREFIX: &str = "output.";

/// Prefix of the estimates read from the residual in a suggestion's list ("residual_half_width").
pub const RESIDUAL_PREFIX: &str = "residual_";

/// What a size estimate measures.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Quantity {
    /// A hysteresis or dead-zone half-width read from the residual ("half_width").
    HalfWidth,
    /// The input level above which the response flattens ("upper_input").
    UpperInput,
    /// The input level below which the response flattens ("lower_input").
    LowerInput,
    /// The residual's step across u = 0, input-referred ("step").
    Step,
    /// The delay, in samples, by which the model's response explains the residual
    /// ("extra_delay").
    ExtraDelay,
    /// The number of play operators in the dynamic-hysteresis test ("plays").
    Plays,
    /// The refitted model's order ("order").
    Order,
    /// The refitted model's input delay ("delay").
    Delay,
    /// A parameter of the refitted model's nonlinearity, by its name ("a", "z1", "w3", or a user
    /// basis's).
    Parameter(String),
    /// A parameter of the refitted model's output map, by its name (shown "output.c2").
    OutputMap(String),
    /// A user candidate's own quantity, by name.
    User(String),
}

impl Quantity {
    /// The name the output shows ("half_width", "a", "output.c2", …).
    pub fn name(&self) -> Cow<'_, str> {
        Cow::Borrowed(match self {
            Quantity::HalfWidth => "half_width",
            Quantity::UpperInput => "upper_input",
            Quantity::LowerInput => "lower_input",
            Quantity::Step => "step",
            Quantity::ExtraDelay => "extra_delay",
            Quantity::Plays => "plays",
            Quantity::Order => "order",
            Quantity::Delay => "delay",
            Quantity::Parameter(n) | Quantity::User(n) => n,
            Quantity::OutputMap(n) => return Cow::Owned(format!("{OUTPUT_MAP_PREFIX}{n}")),
        })
    }
}

impl std::fmt::Display for Quantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(&self.name())
    }
}

/// Where an estimate was read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Source {
    /// From the residual of the model under diagnosis (a candidate's evidence).
    Residual,
    /// From the refitted model (a candidate's refit).
    Refit,
}

/// One size estimate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Estimate {
    /// What it measures.
    pub quantity: Quantity,
    /// Where it was read.
    pub source: Source,
    /// Its value (input units unless the quantity says otherwise).
    pub value: f64,
    /// Its standard error, when the fit computed one (`+∞`: the record does not determine it).
    pub standard_error: Option<f64>,
}

impl Serialize for Quantity {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl Estimate {
    /// An estimate read from the residual (no standard error).
    pub fn residual(quantity: Quantity, value: f64) -> Self {
        Self {
            quantity,
            source: Source::Residual,
            value,
            standard_error: None,
        }
    }

    /// An estimate from the refitted model.
    pub fn refit(quantity: Quantity, value: f64, standard_error: Option<f64>) -> Self {
        Self {
            quantity,
            source: Source::Refit,
            value,
            standard_error,
        }
    }

    /// The name the output shows: the quantity's, prefixed with [`RESIDUAL_PREFIX`] when read
    /// from the residual ("residual_half_width", "a", "output.c2").
    pub fn key(&self) -> String {
        match self.source {
            Source::Residual => format!("{RESIDUAL_PREFIX}{}", self.quantity),
            Source::Refit => self.quantity.name().into_owned(),
        }
    }
}

/// Size estimates, one per name ([`Estimate::key`]), in the order of their names.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Estimates(Vec<Estimate>);

impl Estimates {
    /// No estimate.
    pub fn new() -> Self {
        Self::default()
    }

    /// The estimates read from the residual: the finite values of `pairs`.
    pub fn residual(pairs: impl IntoIterator<Item = (Quantity, Option<f64>)>) -> Self {
        pairs
            .into_iter()
            .filter_map(|(q, v)| {
                v.filter(|x| x.is_finite())
                    .map(|x| Estimate::residual(q, x))
            })
            .collect()
    }

    /// The refitted `model`'s nonlinearity parameters named in `names`, with their standard
    /// errors (names the model does not have are left out).
    pub fn of_parameters<T: Real>(model: &HammersteinModel<T>, names: &[&str]) -> Self {
        model
            .parameters_with_errors()
            .into_iter()
            .filter(|(name, _, _)| names.contains(&name.as_str()))
            .map(|(name, v, se)| Estimate::refit(Quantity::Parameter(name), v, se))
            .collect()
    }

    /// Adds `e`, replacing the estimate of the same name.
    pub fn insert(&mut self, e: Estimate) {
        let key = e.key();
        match self.0.binary_search_by(|x| x.key().cmp(&key)) {
            Ok(i) => self.0[i] = e,
            Err(i) => self.0.insert(i, e),
        }
    }

    /// Adds `e` unless an estimate of the same name is there.
    pub fn insert_missing(&mut self, e: Estimate) {
        let key = e.key();
        if let Err(i) = self.0.binary_search_by(|x| x.key().cmp(&key)) {
            self.0.insert(i, e);
        }
    }

    /// The estimate of `quantity` read from `source`.
    pub fn get(&self, source: Source, quantity: &Quantity) -> Option<&Estimate> {
        self.0
            .iter()
            .find(|e| e.source == source && &e.quantity == quantity)
    }

    /// The refitted model's nonlinearity parameter `name`.
    pub fn parameter(&self, name: &str) -> Option<&Estimate> {
        self.0.iter().find(|e| {
            e.source == Source::Refit && matches!(&e.quantity, Quantity::Parameter(n) if n == name)
        })
    }

    /// The estimates, in the order of their names.
    pub fn iter(&self) -> std::slice::Iter<'_, Estimate> {
        self.0.iter()
    }

    /// The number of estimates.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// "name = value" of each estimate, four decimals, joined by ", " (what the command line
    /// and the report show); an unbounded saturation limit as `-inf` / `inf`.
    pub fn text(&self) -> String {
        self.0
            .iter()
            .map(|e| {
                format!(
                    "{} = {}",
                    e.key(),
                    crate::regressors::limit_text(e.value, 4)
                )
            })
            .collect::<Vec<_>>()
            .join(", ")
    }
}

impl FromIterator<Estimate> for Estimates {
    fn from_iter<I: IntoIterator<Item = Estimate>>(iter: I) -> Self {
        let mut out = Self::new();
        for e in iter {
            out.insert(e);
        }
        out
    }
}

impl<'a> IntoIterator for &'a Estimates {
    type Item = &'a Estimate;
    type IntoIter = std::slice::Iter<'a, Estimate>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}

impl IntoIterator for Estimates {
    type Item = Estimate;
    type IntoIter = std::vec::IntoIter<Estimate>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.into_iter()
    }
}

impl Serialize for Estimates {
    /// The map name → value.
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for e in &self.0 {
            map.serialize_entry(&e.key(), &e.value)?;
        }
        map.end()
    }
}

/// The map name → standard error of the estimates that have one.
struct StandardErrors<'a>(&'a Estimates);

impl Serialize for StandardErrors<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let with: Vec<(String, f64)> = self
            .0
            .iter()
            .filter_map(|e| e.standard_error.map(|se| (e.key(), se)))
            .collect();
        let mut map = s.serialize_map(Some(with.len()))?;
        for (k, se) in &with {
            map.serialize_entry(k, se)?;
        }
        map.end()
    }
}

/// Serialises `estimates` as two fields, `estimate` (name → value) and `standard_errors`
/// (name → standard error, for those that have one): a refit's JSON.
pub(crate) fn values_and_errors<S: Serializer>(
    estimates: &Estimates,
    s: S,
) -> Result<S::Ok, S::Error> {
    let mut st = s.serialize_struct("Estimates", 2)?;
    st.serialize_field("estimate", estimates)?;
    st.serialize_field("standard_errors", &StandardErrors(estimates))?;
    st.end()
}

#[cfg(test)]
mod unit {
    use super::*;

    #[test]
    fn names_order_and_json() {
        let mut e: Estimates = [
            Estimate::refit(Quantity::Parameter("z1".into()), 0.8, Some(0.01)),
            Estimate::residual(Quantity::HalfWidth, 0.2),
            Estimate::refit(Quantity::OutputMap("c2".into()), -0.1, None),
            Estimate::refit(Quantity::Order, 3.0, None),
        ]
        .into_iter()
        .collect();
        // in the order of the names, as the former map of names
        let keys: Vec<String> = e.iter().map(Estimate::key).collect();
        assert_eq!(keys, ["order", "output.c2", "residual_half_width", "z1"]);
        // one per name: inserting replaces, insert_missing keeps
        e.insert(Estimate::refit(Quantity::Order, 4.0, None));
        e.insert_missing(Estimate::refit(Quantity::Parameter("z1".into()), 9.0, None));
        assert_eq!(e.len(), 4);
        assert_eq!(e.get(Source::Refit, &Quantity::Order).unwrap().value, 4.0);
        assert_eq!(e.parameter("z1").unwrap().value, 0.8);
        assert!(e.get(Source::Refit, &Quantity::HalfWidth).is_none());
        assert_eq!(
            serde_json::to_string(&e).unwrap(),
            r#"{"order":4.0,"output.c2":-0.1,"residual_half_width":0.2,"z1":0.8}"#
        );
        assert_eq!(
            e.text(),
            "order = 4.0000, output.c2 = -0.1000, residual_half_width = 0.2000, z1 = 0.8000"
        );
        // the residual's estimates keep the finite values only
        let r = Estimates::residual([
            (Quantity::UpperInput, Some(1.5)),
            (Quantity::LowerInput, Some(f64::NAN)),
            (Quantity::Step, None),
        ]);
        assert_eq!(r.len(), 1);
        assert_eq!(r.iter().next().unwrap().key(), "residual_upper_input");
    }

    #[test]
    fn a_refit_serialises_values_and_standard_errors() {
        #[derive(Serialize)]
        struct R {
            #[serde(flatten, serialize_with = "values_and_errors")]
            estimate: Estimates,
        }
        let r = R {
            estimate: [
                Estimate::refit(Quantity::Parameter("a".into()), 0.5, Some(0.01)),
                Estimate::refit(Quantity::Delay, 2.0, None),
            ]
            .into_iter()
            .collect(),
        };
        assert_eq!(
            serde_json::to_string(&r).unwrap(),
            r#"{"estimate":{"a":0.5,"delay":2.0},"standard_errors":{"a":0.01}}"#
        );
    }
}
