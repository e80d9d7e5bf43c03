//! The tools an evaluation runs on: a tools file's (or table's) rows of one model, or random
//! tools from the model's sampling box.
//!
//! A sample is `toolconf select --models M --tools N --seed S`'s tools exactly (the mixed
//! sampler's documented ChaCha8 stream with one model: [`crate::select::mixed`]), so that any
//! number of the evaluation can be recomputed from `select --json`. A box given by the user
//! (`--box NAME=LO:HI`) replaces the model's box for the parameters it names; the stream and its
//! rule (each parameter lo + (hi − lo)·u in the model's order, a tool that breaks the model's
//! rule drawn again whole) stay the same.

use rand::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

use toolconf_messages::{Clip, Short};
use toolconf_model::inputs::tools_file::ToolRow;
use toolconf_model::registry::{AnyTool, ModelKind};

/// Draws of one tool before a box is called empty of valid tools.
const MAX_REDRAWS: usize = 10_000;

/// The population: its tools, their names and rows, and what it is.
#[derive(Debug, Clone, PartialEq)]
pub struct Population {
    pub tools: Vec<AnyTool>,
    /// A tools file's names (`None` for a row without one, and for random tools).
    pub names: Vec<Option<String>>,
    /// A tools file's 1-based rows; 1 … N for random tools.
    pub rows: Vec<usize>,
    /// "random tools from model panda's sampling box (seed 7)" or "tools file t.csv".
    pub source: String,
    /// The sampling box, (name, lo, hi) per parameter, for a random population.
    pub sample_box: Option<Vec<(String, f64, f64)>>,
}

impl Population {
    pub fn len(&self) -> usize {
        self.tools.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tools.is_empty()
    }

    /// Tool `i`'s label: its name, else `tool i` (0-based, as the CSVs number tools).
    pub fn label(&self, i: usize) -> String {
        match &self.names[i] {
            Some(name) => Clip(name).to_string(),
            None => format!("tool {i}"),
        }
    }

    /// A tools file's rows, every one a tool of `model` (else the error names the row).
    pub fn from_rows(rows: Vec<ToolRow>, model: ModelKind, source: &str) -> Result<Self, String> {
        if let Some(r) = rows.iter().find(|r| r.tool.model() != model) {
            return Err(format!(
                "{source}, tool {} ({}): a {} tool, but the evaluation is of model {model}; \
                 give a tools file of {model} tools",
                r.row,
                r.label(),
                r.tool.model()
            ));
        }
        if let Some(r) = rows.iter().find(|r| !r.missing_tip().is_empty()) {
            return Err(format!(
                "{source}, tool {} ({}): no {} column: a tip task needs each tool's tip",
                r.row,
                r.label(),
                r.missing_tip().join(", ")
            ));
        }
        Ok(Self {
            names: rows.iter().map(|r| r.name.clone()).collect(),
            rows: rows.iter().map(|r| r.row).collect(),
            tools: rows.into_iter().map(|r| r.tool).collect(),
            source: format!("the tools of {source}"),
            sample_box: None,
        })
    }

    /// `n` random tools of `model` drawn from `seed`: with no `overrides`, `select --models
    /// model --tools n --seed seed`'s tools; each override (name, lo, hi) replaces that
    /// parameter's interval (checked by [`sample_box`]).
    pub fn sample(
        model: ModelKind,
        n: usize,
        seed: u64,
        overrides: &[(String, f64, f64)],
    ) -> Result<Self, String> {
        let bounds = sample_box(model, overrides)?;
        let tools = if overrides.is_empty() {
            crate::select::mixed::draw_mixed_tools(&[model], n, seed).map_err(|e| e.to_string())?
        } else {
            draw(model, &bounds, n, seed)?
        };
        let names = model.parameter_names();
        Ok(Self {
            names: vec![None; n],
            rows: (1..=n).collect(),
            tools,
            source: format!(
                "{n} random tools from model {model}'s sampling box{} (seed {seed})",
                if overrides.is_empty() {
                    ""
                } else {
                    ", with --box"
                }
            ),
            sample_box: Some(
                names
                    .iter()
                    .zip(&bounds)
                    .map(|(n, (lo, hi))| (n.to_string(), *lo, *hi))
                    .collect(),
            ),
        })
    }
}

/// The model's sampling box with `overrides` (name, lo, hi) in place: each name one of the
/// model's parameters, lo < hi, both within the parameter's domain.
pub fn sample_box(
    model: ModelKind,
    overrides: &[(String, f64, f64)],
) -> Result<Vec<(f64, f64)>, String> {
    let names = model.parameter_names();
    let mut bounds = model.sample_box().to_vec();
    if bounds.len() != names.len() {
        return Err(format!(
            "model {model} has no sampling box for its tools: give a tools file (--tools)"
        ));
    }
    for (name, lo, hi) in overrides {
        let Some(i) = names.iter().position(|n| n == name) else {
            return Err(format!(
                "--box {}: model {model} has no parameter '{}' (its parameters: {})",
                Clip(name),
                Clip(name),
                names.join(", ")
            ));
        };
        let domain = &model.parameter_domains()[i];
        if !(lo < hi) || !domain.contains(*lo) || !domain.contains(*hi) {
            return Err(format!(
                "--box {name}={}:{}: needs lo < hi, both {} ({name}'s domain)",
                Short(*lo),
                Short(*hi),
                domain.rule
            ));
        }
        bounds[i] = (*lo, *hi);
    }
    Ok(bounds)
}

/// `n` tools of `model` from `bounds`, on the mixed sampler's stream.
fn draw(
    model: ModelKind,
    bounds: &[(f64, f64)],
    n: usize,
    seed: u64,
) -> Result<Vec<AnyTool>, String> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut uniform = move || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let mut tools = Vec::with_capacity(n);
    for _ in 0..n {
        let tool = (0..MAX_REDRAWS).find_map(|_| {
            let p: Vec<f64> = bounds
                .iter()
                .map(|&(lo, hi)| lo + (hi - lo) * uniform())
                .collect();
            AnyTool::new(model, &p).ok()
        });
        tools.push(tool.ok_or_else(|| {
            format!(
                "--box: no valid {model} tool in {MAX_REDRAWS} draws from the box (the model's \
                 rule, e.g. the inertia's triangle inequality, holds nowhere in it)"
            )
        })?);
    }
    Ok(tools)
}

/// `NAME=LO:HI`, as `--box` takes it.
pub fn parse_box(text: &str) -> Result<(String, f64, f64), String> {
    let shape = || {
        format!(
            "--box {}: expected NAME=LO:HI, e.g. tool_mass=0.1:2",
            Clip(text)
        )
    };
    let (name, range) = text.split_once('=').ok_or_else(shape)?;
    let (lo, hi) = range.split_once(':').ok_or_else(shape)?;
    let number = |v: &str| v.trim().parse::<f64>().map_err(|_| shape());
    Ok((name.trim().to_string(), number(lo)?, number(hi)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sample_is_selects_tools_and_a_box_keeps_the_stream() {
        let p = Population::sample(ModelKind::Panda, 5, 7, &[]).unwrap();
        let select = crate::select::mixed::draw_mixed_tools(&[ModelKind::Panda], 5, 7).unwrap();
        assert_eq!(p.tools, select);
        // A box equal to the model's own draws the same tools by the same rule.
        let own: Vec<(String, f64, f64)> = ModelKind::Panda
            .parameter_names()
            .iter()
            .zip(ModelKind::Panda.sample_box())
            .map(|(n, (lo, hi))| (n.to_string(), *lo, *hi))
            .collect();
        assert_eq!(
            draw(
                ModelKind::Panda,
                &sample_box(ModelKind::Panda, &own).unwrap(),
                5,
                7
            )
            .unwrap(),
            select
        );
        let narrow =
            Population::sample(ModelKind::Panda, 50, 7, &[("tool_mass".into(), 1.0, 1.5)]).unwrap();
        assert!(narrow
            .tools
            .iter()
            .all(|t| (1.0..1.5).contains(&t.parameters()[0])));
        let e = Population::sample(ModelKind::Panda, 5, 7, &[("tool_lenght".into(), 1.0, 2.0)])
            .unwrap_err();
        assert!(
            e.contains("--box tool_lenght") && e.contains("tool_mass"),
            "{e}"
        );
        let e = Population::sample(ModelKind::Panda, 5, 7, &[("tool_mass".into(), 2.0, 1.0)])
            .unwrap_err();
        assert!(e.contains("lo < hi"), "{e}");
        assert_eq!(parse_box("m1=0.1:0.5").unwrap(), ("m1".into(), 0.1, 0.5));
        assert!(parse_box("m1=0.1").is_err());
    }
}
