//! Physical effects of an actuator nonlinearity and sets of them (the UDN's 16 subsets).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// A physical effect a static actuator nonlinearity can contain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// Hysteresis: the branch shifts by ±a with the input's direction of motion.
    Hysteresis,
    /// Dead-zone: no output inside |x| ≤ b.
    DeadZone,
    /// Saturation: output clamped to p·z2 ≤ v ≤ p·z1.
    Saturation,
    /// Preload: a step e1 / e2 where the branch leaves the dead band.
    Preload,
    /// Dynamic (rate-independent, amplitude-dependent) hysteresis: a Prandtl–Ishlinskii sum of
    /// weighted play operators added to the UDN's output (`regressors::PrandtlIshlinskii`).
    PrandtlIshlinskii,
}

impl Effect {
    /// The UDN's four effects, in the UDN's order (the Prandtl–Ishlinskii basis is not one of
    /// them: see [`Effect::PrandtlIshlinskii`]).
    pub const ALL: [Effect; 4] = [
        Effect::Hysteresis,
        Effect::DeadZone,
        Effect::Saturation,
        Effect::Preload,
    ];

    /// Name as the command line spells it ("hysteresis", "dead-zone", "saturation", "preload").
    pub fn name(self) -> &'static str {
        match self {
            Effect::Hysteresis => "hysteresis",
            Effect::DeadZone => "dead-zone",
            Effect::Saturation => "saturation",
            Effect::Preload => "preload",
            Effect::PrandtlIshlinskii => "prandtl-ishlinskii",
        }
    }

    fn bit(self) -> u8 {
        match self {
            Effect::Hysteresis => 1,
            Effect::DeadZone => 2,
            Effect::Saturation => 4,
            Effect::Preload => 8,
            Effect::PrandtlIshlinskii => 16,
        }
    }
}

impl std::fmt::Display for Effect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Effect {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().replace('_', "-").as_str() {
            "hysteresis" | "backlash" => Ok(Effect::Hysteresis),
            "dead-zone" | "deadzone" => Ok(Effect::DeadZone),
            "saturation" => Ok(Effect::Saturation),
            "preload" => Ok(Effect::Preload),
            "prandtl-ishlinskii" | "pi" => Ok(Effect::PrandtlIshlinskii),
            other => Err(Error::UnknownName {
                kind: crate::error::NameKind::Effect,
                name: other.to_string(),
                expected: "hysteresis, dead-zone, saturation, preload, prandtl-ishlinskii, or linear",
            }),
        }
    }
}

/// A subset of the four UDN effects, optionally with the Prandtl–Ishlinskii basis; the empty set
/// is a pure linear gain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(into = "Vec<Effect>", from = "Vec<Effect>")]
pub struct EffectSet(u8);

impl EffectSet {
    /// No effect: a linear gain.
    pub const fn empty() -> Self {
        EffectSet(0)
    }
    /// All four UDN effects: the full UDN (without the Prandtl–Ishlinskii basis).
    pub const fn all() -> Self {
        EffectSet(15)
    }
    /// Builds a set from a list of effects.
    pub fn of(effects: &[Effect]) -> Self {
        effects.iter().fold(Self::empty(), |s, &e| s.with(e))
    }
    /// Parses a comma-separated list ("saturation,hysteresis"); "" or "linear" is the empty set.
    pub fn parse(s: &str) -> Result<Self> {
        let t = s.trim();
        if t.is_empty() || t.eq_ignore_ascii_case("linear") || t.eq_ignore_ascii_case("none") {
            return Ok(Self::empty());
        }
        if t.eq_ignore_ascii_case("all") || t.eq_ignore_ascii_case("udn") {
            return Ok(Self::all());
        }
        let mut set = Self::empty();
        for part in t.split(',').filter(|p| !p.trim().is_empty()) {
            set = set.with(part.parse()?);
        }
        Ok(set)
    }
    /// The set with `e` added.
    pub fn with(self, e: Effect) -> Self {
        EffectSet(self.0 | e.bit())
    }
    /// The set with `e` removed.
    pub fn without(self, e: Effect) -> Self {
        EffectSet(self.0 & !e.bit())
    }
    /// True when `e` is in the set.
    pub fn contains(self, e: Effect) -> bool {
        self.0 & e.bit() != 0
    }
    /// True for the empty set (linear gain).
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
    /// Number of effects in the set.
    pub fn len(self) -> usize {
        self.0.count_ones() as usize
    }
    /// The effects in the set, in the UDN's order, the Prandtl–Ishlinskii basis last.
    pub fn effects(self) -> Vec<Effect> {
        Effect::ALL
            .into_iter()
            .chain([Effect::PrandtlIshlinskii])
            .filter(|&e| self.contains(e))
            .collect()
    }
    /// The set's UDN effects alone (the Prandtl–Ishlinskii basis removed).
    pub fn udn_part(self) -> Self {
        self.without(Effect::PrandtlIshlinskii)
    }
    /// All 16 subsets of the UDN effects, from the empty one to the full UDN.
    pub fn all_subsets() -> Vec<EffectSet> {
        (0u8..16).map(EffectSet).collect()
    }
    /// The paper's Table 1 name (1..=8 for DN1..DN8) when the set is one of them.
    ///
    /// DN1/DN2 (a = b) are hysteresis + dead-zone with tied widths; they are reported as DN3/DN1's
    /// untied forms: DN1 = {H, DZ, S, P} with a = b, here any set with hysteresis, dead-zone,
    /// saturation and preload is reported as DN1, {H, DZ, S} as DN3.
    pub fn dn_type(self) -> Option<u8> {
        use Effect::*;
        let h = self.contains(Hysteresis);
        let dz = self.contains(DeadZone);
        let s = self.contains(Saturation);
        let p = self.contains(Preload);
        if !s || self.contains(PrandtlIshlinskii) {
            return None;
        }
        match (h, dz, p) {
            (true, true, true) => Some(1),
            (true, true, false) => Some(3),
            (true, false, false) => Some(4),
            (false, true, true) => Some(5),
            (false, false, true) => Some(6),
            (false, true, false) => Some(7),
            (false, false, false) => Some(8),
            (true, false, true) => None,
        }
    }
    /// Comma-separated names ("linear" for the empty set).
    pub fn label(self) -> String {
        if self.is_empty() {
            "linear".into()
        } else {
            self.effects()
                .iter()
                .map(|e| e.name())
                .collect::<Vec<_>>()
                .join(",")
        }
    }
}

impl From<EffectSet> for Vec<Effect> {
    fn from(s: EffectSet) -> Self {
        s.effects()
    }
}

impl From<Vec<Effect>> for EffectSet {
    fn from(v: Vec<Effect>) -> Self {
        EffectSet::of(&v)
    }
}

impl std::fmt::Display for EffectSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.label())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_round_trip_and_errors() {
        let s = EffectSet::parse("saturation, hysteresis").unwrap();
        assert!(s.contains(Effect::Saturation) && s.contains(Effect::Hysteresis));
        assert_eq!(s.len(), 2);
        assert_eq!(EffectSet::parse(&s.label()).unwrap(), s);
        assert_eq!(s.dn_type(), Some(4));
        assert!(EffectSet::parse("linear").unwrap().is_empty());
        assert!(EffectSet::parse("hysteresys").is_err());
        assert_eq!(EffectSet::all_subsets().len(), 16);
        let pi = EffectSet::parse("saturation,prandtl-ishlinskii").unwrap();
        assert!(pi.contains(Effect::PrandtlIshlinskii) && pi.len() == 2);
        assert_eq!(EffectSet::parse(&pi.label()).unwrap(), pi);
        assert_eq!(pi.udn_part(), EffectSet::of(&[Effect::Saturation]));
        assert_eq!(pi.dn_type(), None);
    }
}
