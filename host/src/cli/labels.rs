//! `--labels`: the command line's name for [`LabelSource`], so that clap stays in `cli`.

use crate::dataset::frame::LabelSource;

/// Which labels to attach to points (`--labels` of `map`, `export` and `compare`); the
/// variants, their spelling (`gt`, `pred`, `pred-topk`, `none`) and their help are those of
/// [`LabelSource`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum LabelArg {
    /// Ground-truth labels (void pixels add geometry only).
    Gt,
    /// Predicted top-1 labels.
    Pred,
    /// Predicted top-k labels with scores.
    PredTopk,
    /// No labels: geometry only.
    None,
}

impl From<LabelArg> for LabelSource {
    fn from(a: LabelArg) -> LabelSource {
        match a {
            LabelArg::Gt => LabelSource::Gt,
            LabelArg::Pred => LabelSource::Pred,
            LabelArg::PredTopk => LabelSource::PredTopk,
            LabelArg::None => LabelSource::None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::ValueEnum;

    #[test]
    fn every_label_source_has_its_own_spelling() {
        let spelled: Vec<(String, LabelSource)> = LabelArg::value_variants()
            .iter()
            .map(|v| {
                (
                    v.to_possible_value().unwrap().get_name().to_string(),
                    (*v).into(),
                )
            })
            .collect();
        assert_eq!(
            spelled,
            [
                ("gt".to_string(), LabelSource::Gt),
                ("pred".to_string(), LabelSource::Pred),
                ("pred-topk".to_string(), LabelSource::PredTopk),
                ("none".to_string(), LabelSource::None),
            ]
        );
    }
}
