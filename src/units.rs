//! Physical units read from a column name: `force [N]`, `force (N)`, `force_N`,
//! `vel_cm_s` (cm/s), `acc_m_s2` (m/s²).

/// Unit symbols recognised as a name's trailing `_`-separated tokens.
const SYMBOLS: &[&str] = &[
    "V", "mV", "kV", "A", "mA", "N", "kN", "mN", "Nm", "m", "cm", "mm", "um", "km", "s", "ms",
    "min", "h", "Hz", "rad", "deg", "degC", "C", "K", "Pa", "kPa", "MPa", "bar", "W", "kW", "g",
    "kg", "l", "L", "rpm", "pct",
];

/// The unit a column name carries, if any: the text inside a trailing `[…]` or `(…)`, or the
/// trailing `_`-separated tokens that are all unit symbols ("vel_cm_s" → "cm/s", "acc_m_s2" →
/// "m/s²", "force_N" → "N"). A name without an underscore or bracket has no unit ("u", "y").
pub fn unit_of(name: &str) -> Option<String> {
    let name = name.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if name.ends_with(close)
            && let Some(i) = name.rfind(open)
        {
            let inner = name[i + open.len_utf8()..name.len() - close.len_utf8()].trim();
            return (!inner.is_empty()).then(|| inner.to_string());
        }
    }
    let tokens: Vec<&str> = name.split('_').collect();
    if tokens.len() < 2 {
        return None;
    }
    // the longest tail of unit tokens, the quantity's name left in front of it
    let mut start = tokens.len();
    while start > 1 && is_unit_token(tokens[start - 1]) {
        start -= 1;
    }
    if start == tokens.len() {
        return None;
    }
    let units = &tokens[start..];
    let mut out = units[0].to_string();
    for t in &units[1..] {
        // a following time or length unit divides ("cm_s" = cm/s, "m_s2" = m/s²)
        out.push('/');
        out.push_str(&power(t));
    }
    Some(out)
}

fn is_unit_token(t: &str) -> bool {
    let base = t.trim_end_matches(|c: char| c.is_ascii_digit());
    SYMBOLS.contains(&base) && !base.is_empty()
}

fn power(t: &str) -> String {
    let base = t.trim_end_matches(|c: char| c.is_ascii_digit());
    match &t[base.len()..] {
        "" | "1" => base.to_string(),
        "2" => format!("{base}²"),
        "3" => format!("{base}³"),
        p => format!("{base}^{p}"),
    }
}

#[cfg(test)]
mod tests {
    use super::unit_of;

    #[test]
    fn units_from_names() {
        assert_eq!(unit_of("force_N").as_deref(), Some("N"));
        assert_eq!(unit_of("voltage_V").as_deref(), Some("V"));
        assert_eq!(unit_of("vel_cm_s").as_deref(), Some("cm/s"));
        assert_eq!(unit_of("acc_m_s2").as_deref(), Some("m/s²"));
        assert_eq!(unit_of("qm_m").as_deref(), Some("m"));
        assert_eq!(unit_of("t_min").as_deref(), Some("min"));
        assert_eq!(unit_of("force [kN]").as_deref(), Some("kN"));
        assert_eq!(unit_of("y (mm)").as_deref(), Some("mm"));
        assert_eq!(unit_of("u"), None);
        assert_eq!(unit_of("y1"), None);
        assert_eq!(unit_of("acc1"), None);
        assert_eq!(unit_of("pulses_N").as_deref(), Some("N"));
        assert_eq!(unit_of("my_signal"), None);
        assert_eq!(unit_of("x []"), None);
    }
}
