//! `--labels`: the command line's name for [`LabelSource`], so that clap stays in `cli`.

use crate::dataset::frame::LabelSource;
use crate::dataset::source::Dataset;
use clap::ValueEnum;

/// Which labels to attach to points (`--labels` of `map`, `export` and `compare`; a list of
/// `gt` and `pred` in `experiment`); the variants, their spelling (`gt`, `pred`, `pred-topk`, `none`) and their help are those of
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

/// The value parser of `--labels` where only ground-truth and predicted top-1 labels can
/// be run (`sndt experiment`, the paper's comparison): `gt` and `pred`, spelled and meaning
/// as in [`LabelArg`]; `--help` lists only these two, and any other value is refused with
/// the two named.
///
/// ```
/// use clap::Parser;
/// use sndt_host::cli::labels::{gt_or_pred, LabelArg};
/// #[derive(Parser)]
/// struct Line {
///     #[arg(long, value_delimiter = ',', value_parser = gt_or_pred())]
///     labels: Vec<LabelArg>,
/// }
/// let line = Line::try_parse_from(["x", "--labels", "gt,pred"]).unwrap();
/// assert_eq!(line.labels, [LabelArg::Gt, LabelArg::Pred]);
/// assert!(Line::try_parse_from(["x", "--labels", "pred-topk"]).is_err());
/// ```
pub fn gt_or_pred() -> impl clap::builder::TypedValueParser<Value = LabelArg> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(["gt", "pred"])
        .try_map(|name| LabelArg::from_str(&name, false))
}

/// Refuses `--labels pred` / `pred-topk` for a dataset without predictions (the map would
/// get no labels and score 0 %): the message says where predictions were looked for.
///
/// ```
/// use sndt_host::cli::labels::{check_labels, LabelArg};
/// use sndt_host::dataset::synthetic::{SynthOptions, Synthetic};
/// let plain = Synthetic::new(SynthOptions { scenes: 1, frames: 1, predictions: false, ..Default::default() }).unwrap();
/// let e = check_labels(LabelArg::Pred, &plain, "synthetic").unwrap_err();
/// assert!(e.to_string().starts_with("--labels pred: synthetic has no predictions"));
/// assert!(check_labels(LabelArg::Gt, &plain, "synthetic").is_ok());
/// ```
pub fn check_labels(labels: LabelArg, dataset: &dyn Dataset, name: &str) -> anyhow::Result<()> {
    if matches!(labels, LabelArg::Pred | LabelArg::PredTopk)
        && let Some(place) = dataset.missing_predictions()
    {
        let option = labels.to_possible_value().map(|v| v.get_name().to_string());
        anyhow::bail!(
            "--labels {}: {name} has no predictions: {place}",
            option.unwrap_or_default()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

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
