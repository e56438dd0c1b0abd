//! The paper's Tables 2 and 3 (mean and standard deviation over 50 Monte Carlo runs), transcribed
//! for printing beside the study's numbers.
//!
//! Source: "Subspace Identification of Hammerstein Model with Unified Discontinuous Nonlinearity",
//! Section 4.1, Table 2 (UDN structure assumed; SNR: none, 10, 8 dB) and Table 3 (exact SH
//! structure; SNR: none, 10, 8, 5 dB). Table 3's numerator "b0, b1" is stored as b1, b2 (eq. 22).
//! Table 2 prints the std of e1 at 10 dB as −0.0573; a standard deviation is non-negative, so
//! 0.0573 is stored.

/// One row pair (mean, std) of a paper table at one SNR.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PaperRow {
    /// SNR in dB (`None`: "without noise").
    pub snr_db: Option<f64>,
    /// Means l̄_i, in the order of the table's parameter names.
    pub mean: &'static [f64],
    /// Standard deviations σ_li (eq. 23, divisor M).
    pub std: &'static [f64],
}

/// Parameter names of Table 2.
pub const TABLE2_PARAMS: [&str; 11] = [
    "p", "a", "b", "z1", "z2", "e1", "e2", "a1", "a2", "b1", "b2",
];

/// Parameter names of Table 3 (b1, b2 are the paper's b0, b1).
pub const TABLE3_PARAMS: [&str; 8] = ["p", "a", "z1", "z2", "a1", "a2", "b1", "b2"];

/// Table 2: UDN structure assumed.
pub const TABLE2: [PaperRow; 3] = [
    PaperRow {
        snr_db: None,
        mean: &[
            2.0000, 0.5001, 0.0000, 1.5001, -1.0000, 0.0006, 0.0007, -0.2001, 0.3500, 1.0013,
            0.4998,
        ],
        std: &[
            0.0001, 0.0003, 0.0001, 0.0005, 0.0000, 0.0004, 0.0007, 0.0001, 0.0000, 0.0002, 0.0002,
        ],
    },
    PaperRow {
        snr_db: Some(10.0),
        mean: &[
            2.0027, 0.4760, 0.0326, 1.4874, -1.0546, 0.0538, -0.0368, -0.2006, 0.3496, 1.0029,
            0.4898,
        ],
        std: &[
            0.0709, 0.0618, 0.0208, 0.0264, 0.0188, 0.0573, 0.0189, 0.0017, 0.0010, 0.0091, 0.0073,
        ],
    },
    PaperRow {
        snr_db: Some(8.0),
        mean: &[
            2.0741, 0.5341, 0.1018, 1.4210, -0.8515, -0.0715, -0.0290, -0.1980, 0.3488, 1.0385,
            0.4887,
        ],
        std: &[
            0.0388, 0.0106, 0.0287, 0.0941, 0.0963, 0.1068, 0.0327, 0.0016, 0.0022, 0.0247, 0.0783,
        ],
    },
];

/// Table 3: exact SH structure.
pub const TABLE3: [PaperRow; 4] = [
    PaperRow {
        snr_db: None,
        mean: &[
            2.0000, 0.5000, 1.5000, -1.0000, -0.2000, 0.3500, 0.9998, 0.5001,
        ],
        std: &[
            0.0001, 0.0001, 0.0001, 0.0001, 0.0001, 0.0001, 0.0001, 0.0001,
        ],
    },
    PaperRow {
        snr_db: Some(10.0),
        mean: &[
            2.0125, 0.4955, 1.4884, -0.9971, -0.2039, 0.3468, 0.9844, 0.4939,
        ],
        std: &[
            0.0149, 0.0169, 0.0154, 0.0218, 0.0067, 0.0041, 0.0248, 0.0149,
        ],
    },
    PaperRow {
        snr_db: Some(8.0),
        mean: &[
            1.9881, 0.4925, 1.4877, -0.9964, -0.1964, 0.3455, 1.0198, 0.5081,
        ],
        std: &[
            0.0127, 0.0304, 0.0275, 0.0278, 0.0246, 0.0213, 0.0354, 0.0358,
        ],
    },
    PaperRow {
        snr_db: Some(5.0),
        mean: &[
            2.0776, 0.4824, 1.4724, -0.9270, -0.2232, 0.3328, 0.9686, 0.5198,
        ],
        std: &[
            0.0144, 0.0731, 0.0308, 0.0205, 0.0455, 0.0458, 0.0153, 0.0215,
        ],
    },
];

/// The paper's (mean, std) of `param` in table 2 or 3 at `snr_db` (`None` when not reported).
pub fn paper_value(table: u8, snr_db: Option<f64>, param: &str) -> Option<(f64, f64)> {
    let (rows, names): (&[PaperRow], &[&str]) = match table {
        2 => (&TABLE2, &TABLE2_PARAMS),
        3 => (&TABLE3, &TABLE3_PARAMS),
        _ => return None,
    };
    let row = rows.iter().find(|r| r.snr_db == snr_db)?;
    let i = names.iter().position(|&n| n == param)?;
    Some((row.mean[i], row.std[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_complete_and_lookups_work() {
        for r in TABLE2 {
            assert_eq!(r.mean.len(), TABLE2_PARAMS.len());
            assert_eq!(r.std.len(), TABLE2_PARAMS.len());
            assert!(r.std.iter().all(|&s| s >= 0.0));
        }
        for r in TABLE3 {
            assert_eq!(r.mean.len(), TABLE3_PARAMS.len());
            assert_eq!(r.std.len(), TABLE3_PARAMS.len());
        }
        // NOTES.md's quoted figures
        assert_eq!(paper_value(2, Some(8.0), "z2"), Some((-0.8515, 0.0963)));
        assert_eq!(paper_value(3, Some(5.0), "a"), Some((0.4824, 0.0731)));
        assert_eq!(paper_value(3, Some(10.0), "b"), None);
        assert_eq!(paper_value(3, Some(3.0), "p"), None);
    }
}
