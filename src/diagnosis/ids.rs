//! The typed keys of the diagnosis: which residual test ([`TestId`]) and which candidate effect
//! ([`CandidateId`]). Both print and serialise as the names the command line and its JSON show
//! ("input-direction", "hysteresis", …); a user's test or candidate is `User(name)`.

use crate::regressors::Effect;
use serde::{Serialize, Serializer};

/// Which residual test a [`TestResult`](super::TestResult) is.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TestId {
    /// Ljung–Box whiteness of the residual ("whiteness").
    Whiteness,
    /// Cross-correlation of the residual with the input ("input-cross-correlation").
    InputCrossCorrelation,
    /// An FIR of v̂ beyond the model's response: linear dynamics missing ("dynamics").
    Dynamics,
    /// The model's response shifted in time: a delay mismatch ("delay").
    Delay,
    /// Binned input level ("input-level").
    InputLevel,
    /// Rising against falling input: hysteresis ("input-direction").
    InputDirection,
    /// Slopes beyond the input's extreme deciles: saturation ("input-extremes").
    InputExtremes,
    /// Slope for small |u|: dead-zone ("input-near-zero").
    InputNearZero,
    /// Step across u = 0: preload ("input-zero-step").
    InputZeroStep,
    /// Correlation with u² ("input-square").
    InputSquare,
    /// Correlation with u³ ("input-cube").
    InputCube,
    /// Binned predicted output: output nonlinearity ("output-level").
    OutputLevel,
    /// Play operators beyond the level/direction split: dynamic hysteresis
    /// ("prandtl-ishlinskii"; the candidate's own test).
    PrandtlIshlinskii,
    /// Odd functions of the simulated output or its difference beyond the input's bins: a
    /// nonlinearity in feedback ("feedback-nonlinearity"; the candidate's own test).
    FeedbackNonlinearity,
    /// A user's test, by name.
    User(String),
}

impl TestId {
    /// Every built-in test, in the order the built-in registry runs them (the
    /// Prandtl–Ishlinskii candidate's own test last: it is not in the registry).
    pub const BUILTIN: [TestId; 14] = [
        TestId::Whiteness,
        TestId::InputCrossCorrelation,
        TestId::Dynamics,
        TestId::Delay,
        TestId::InputLevel,
        TestId::InputDirection,
        TestId::InputExtremes,
        TestId::InputNearZero,
        TestId::InputZeroStep,
        TestId::InputSquare,
        TestId::InputCube,
        TestId::OutputLevel,
        TestId::PrandtlIshlinskii,
        TestId::FeedbackNonlinearity,
    ];

    /// The name the output shows ("whiteness", "input-direction", …, or the user's).
    pub fn as_str(&self) -> &str {
        match self {
            TestId::Whiteness => "whiteness",
            TestId::InputCrossCorrelation => "input-cross-correlation",
            TestId::Dynamics => "dynamics",
            TestId::Delay => "delay",
            TestId::InputLevel => "input-level",
            TestId::InputDirection => "input-direction",
            TestId::InputExtremes => "input-extremes",
            TestId::InputNearZero => "input-near-zero",
            TestId::InputZeroStep => "input-zero-step",
            TestId::InputSquare => "input-square",
            TestId::InputCube => "input-cube",
            TestId::OutputLevel => "output-level",
            TestId::PrandtlIshlinskii => "prandtl-ishlinskii",
            TestId::FeedbackNonlinearity => "feedback-nonlinearity",
            TestId::User(name) => name,
        }
    }
}

impl From<&str> for TestId {
    /// The built-in test of that name, else `User(name)`.
    fn from(name: &str) -> Self {
        TestId::BUILTIN
            .iter()
            .find(|t| t.as_str() == name)
            .cloned()
            .unwrap_or_else(|| TestId::User(name.to_string()))
    }
}

impl From<String> for TestId {
    fn from(name: String) -> Self {
        TestId::from(name.as_str())
    }
}

/// Which candidate effect a [`MissingEffect`](super::MissingEffect) adds.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CandidateId {
    /// A static effect added to the nonlinearity (the UDN's four, or the Prandtl–Ishlinskii
    /// plays), named as the effect.
    Effect(Effect),
    /// The linear block's order is too low ("dynamics").
    Dynamics,
    /// The input delay is too short ("delay").
    Delay,
    /// An output nonlinearity after the linear block ("output-nonlinearity").
    OutputNonlinearity,
    /// A static nonlinearity in feedback on the output or its difference
    /// ("feedback-nonlinearity").
    FeedbackNonlinearity,
    /// A user's candidate, by name.
    User(String),
}

impl CandidateId {
    /// Every built-in candidate, in the built-in registry's order.
    pub const BUILTIN: [CandidateId; 9] = [
        CandidateId::Effect(Effect::Hysteresis),
        CandidateId::Effect(Effect::DeadZone),
        CandidateId::Effect(Effect::Saturation),
        CandidateId::Effect(Effect::Preload),
        CandidateId::Effect(Effect::PrandtlIshlinskii),
        CandidateId::Dynamics,
        CandidateId::Delay,
        CandidateId::OutputNonlinearity,
        CandidateId::FeedbackNonlinearity,
    ];

    /// A user's candidate named `name` (the built-in one when `name` is a built-in's).
    pub fn user(name: &str) -> Self {
        Self::from(name)
    }

    /// The name the output shows ("hysteresis", "dynamics", …, or the user's).
    pub fn as_str(&self) -> &str {
        match self {
            CandidateId::Effect(e) => e.name(),
            CandidateId::Dynamics => "dynamics",
            CandidateId::Delay => "delay",
            CandidateId::OutputNonlinearity => "output-nonlinearity",
            CandidateId::FeedbackNonlinearity => "feedback-nonlinearity",
            CandidateId::User(name) => name,
        }
    }

    /// The static effect this candidate adds, when it is one.
    pub fn effect(&self) -> Option<Effect> {
        match self {
            CandidateId::Effect(e) => Some(*e),
            _ => None,
        }
    }
}

impl From<&str> for CandidateId {
    /// The built-in candidate of that name, else `User(name)`.
    fn from(name: &str) -> Self {
        CandidateId::BUILTIN
            .iter()
            .find(|c| c.as_str() == name)
            .cloned()
            .unwrap_or_else(|| CandidateId::User(name.to_string()))
    }
}

impl From<String> for CandidateId {
    fn from(name: String) -> Self {
        CandidateId::from(name.as_str())
    }
}

impl From<Effect> for CandidateId {
    fn from(e: Effect) -> Self {
        CandidateId::Effect(e)
    }
}

macro_rules! name_like {
    ($t:ty) => {
        impl std::fmt::Display for $t {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.pad(self.as_str())
            }
        }
        impl Serialize for $t {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.as_str())
            }
        }
        impl PartialEq<str> for $t {
            fn eq(&self, other: &str) -> bool {
                self.as_str() == other
            }
        }
        impl PartialEq<&str> for $t {
            fn eq(&self, other: &&str) -> bool {
                self.as_str() == *other
            }
        }
        impl PartialEq<String> for $t {
            fn eq(&self, other: &String) -> bool {
                self.as_str() == other
            }
        }
    };
}

name_like!(TestId);
name_like!(CandidateId);

#[cfg(test)]
mod unit {
    use super::*;

    #[test]
    fn names_round_trip() {
        for t in TestId::BUILTIN {
            assert_eq!(TestId::from(t.as_str()), t);
        }
        for c in CandidateId::BUILTIN {
            assert_eq!(CandidateId::from(c.as_str()), c);
        }
        assert_eq!(
            CandidateId::user("stiffening"),
            CandidateId::User("stiffening".into())
        );
        assert_eq!(
            serde_json::to_string(&CandidateId::Effect(Effect::DeadZone)).unwrap(),
            "\"dead-zone\""
        );
        assert_eq!(TestId::InputDirection, "input-direction");
    }
}
