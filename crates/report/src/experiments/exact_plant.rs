//! Robustness check: the paper's experiments rerun with the *exact* Lagrangian 2-link arm
//! as the plant, while the agent keeps the paper's model (its A, B, sensitivities and Π^U). The
//! paper's generative process treats link 2 as if its pivot did not accelerate; do claims C1, C2
//! and the Fig. 7 ranking survive when the world is the exact arm?
//!
//! Each wrapped experiment draws the same tools as its paper-plant original (its seed labels are
//! the original's), so the two sections compare the same tools; its files carry the prefix
//! `exact_plant_` and its verdicts the prefix "exact plant: ".

use super::report::{Block, Section};
use super::{Context, Experiment, Plan, ReproduceError};
use toolconf_model::closed_loop::Plant;

/// The prefix of the wrapped experiments' files.
pub const FILE_PREFIX: &str = "exact_plant_";

pub struct OnExactPlant {
    pub inner: Box<dyn Experiment>,
    pub id: &'static str,
    pub title: &'static str,
}

impl Experiment for OnExactPlant {
    fn id(&self) -> &'static str {
        self.id
    }

    fn title(&self) -> &'static str {
        self.title
    }

    fn outputs(&self) -> Vec<String> {
        self.inner
            .outputs()
            .into_iter()
            .map(|f| format!("{FILE_PREFIX}{f}"))
            .collect()
    }

    fn planned_episodes(&self, plan: &Plan) -> u64 {
        self.inner.planned_episodes(plan)
    }

    fn run(&self, ctx: &Context) -> Result<Section, ReproduceError> {
        let exact = Context {
            out_dir: ctx.out_dir,
            seed: ctx.seed,
            plan: ctx.plan,
            options: ctx.options,
            plant: Plant::Exact,
            progress: ctx.progress,
            file_prefix: FILE_PREFIX,
        };
        let mut section = self.inner.run(&exact)?;
        section.id = self.id;
        section.title = self.title.to_string();
        let outputs = self.inner.outputs();
        for block in &mut section.blocks {
            match block {
                Block::Verdict(v) => v.claim = format!("exact plant: {}", v.claim),
                Block::Figure { file, .. } => *file = format!("{FILE_PREFIX}{file}"),
                // The inner experiment names its files without the prefix it was given.
                Block::Paragraph(text) => {
                    for name in &outputs {
                        *text =
                            text.replace(&format!("`{name}`"), &format!("`{FILE_PREFIX}{name}`"));
                    }
                }
                _ => {}
            }
        }
        section.blocks.insert(
            0,
            Block::p(format!(
                "The same experiment and tools as {}, with the exact Lagrangian 2-link dynamics \
                 (generated/arm2_exact.rs) as the plant. The agent is unchanged: it still controls \
                 with, and rates its confidence by, the paper's model, so ln|Π^U| is the same per tool.",
                self.inner.title()
            )),
        );
        Ok(section)
    }
}
