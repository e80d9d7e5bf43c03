//! A tool of any generated model: [`ModelKind`] names a model, [`AnyTool`] holds a validated tool
//! of it. Tool files (`toolconf rank`), mixed tool sets ([`crate::select::mixed`]) and the
//! command line's `--model` take tools this way; the list of models comes from the generated
//! registry, so a new model description needs no edit here.

use std::fmt;
use std::str::FromStr;

use super::*;
use crate::generated;
use crate::generated::validity::ParameterDomain;
use crate::Error;

/// The types over every generated model ([`crate::for_each_model!`]): [`ModelKind`] names a
/// model, [`AnyTool`] holds a tool of any of them.
macro_rules! mixed_models {
    ($(($marker:ident, $module:ident, $tool:ident, $name:literal, $title:literal)),* $(,)?) => {
        /// The models a mixed set can draw from: every generated model.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum ModelKind {
            $(#[doc = $title] $marker,)*
        }

        impl ModelKind {
            pub const ALL: [ModelKind; generated::MODEL_NAMES.len()] = [$(ModelKind::$marker,)*];

            /// The generated module's name.
            pub fn name(self) -> &'static str {
                match self { $(ModelKind::$marker => generated::$module::NAME,)* }
            }

            /// The model's title (its description's `model.title`).
            pub fn title(self) -> &'static str {
                match self { $(ModelKind::$marker => $title,)* }
            }

            /// The control dimension n (joints).
            pub fn dof(self) -> usize {
                match self { $(ModelKind::$marker => generated::$module::DOF,)* }
            }

            /// The tool parameters' names, in the order a tool takes them.
            pub fn parameter_names(self) -> &'static [&'static str] {
                match self { $(ModelKind::$marker => &generated::$module::PARAMETER_NAMES,)* }
            }

            /// The tool parameters' units (kg, m, kg m^2, ...), in the same order.
            pub fn parameter_units(self) -> &'static [&'static str] {
                match self { $(ModelKind::$marker => &generated::$module::PARAMETER_UNITS,)* }
            }

            /// Each tool parameter's domain (`generated::validity`), in the same order.
            pub fn parameter_domains(self) -> &'static [ParameterDomain] {
                match self { $(ModelKind::$marker => &generated::validity::$module::RULE.domains,)* }
            }

            /// The constraints across the tool parameters, each c · p ≤ 0 as (c, its text).
            pub fn parameter_constraints(self) -> Vec<(&'static [f64], &'static str)> {
                match self {
                    $(ModelKind::$marker => generated::validity::$module::RULE
                        .constraints
                        .iter()
                        .map(|c| (&c.coefficients[..], c.rule))
                        .collect(),)*
                }
            }

            /// The box random tools are drawn from, (lo, hi) per parameter.
            pub fn sample_box(self) -> &'static [(f64, f64)] {
                match self { $(ModelKind::$marker => &generated::validity::$module::RULE.sample,)* }
            }

            /// The equilibrium X^e = [q^e; q̇^e] the model is linearised at.
            pub fn equilibrium_state(self) -> &'static [f64] {
                match self { $(ModelKind::$marker => &generated::$module::EQUILIBRIUM_STATE,)* }
            }

            /// The equilibrium torque U^e.
            pub fn equilibrium_control(self) -> &'static [f64] {
                match self { $(ModelKind::$marker => &generated::$module::EQUILIBRIUM_CONTROL,)* }
            }
        }

        /// A tool of any model.
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum AnyTool {
            $($marker($tool),)*
        }

        impl AnyTool {
            pub fn model(&self) -> ModelKind {
                match self { $(AnyTool::$marker(_) => ModelKind::$marker,)* }
            }

            /// (name, value) of every parameter, in the model's order.
            pub fn named_parameters(&self) -> Vec<(&'static str, f64)> {
                match self { $(AnyTool::$marker(t) => t.named_parameters().to_vec(),)* }
            }

            /// Builds a validated tool of `model` from its parameters in the model's order.
            pub fn new(model: ModelKind, params: &[f64]) -> Result<Self, Error> {
                let count = || Error::ParameterCount {
                    model: model.name(),
                    expected: model.parameter_names().len(),
                    names: model.parameter_names().join(","),
                    found: params.len(),
                };
                Ok(match model {
                    $(ModelKind::$marker => {
                        AnyTool::$marker(ToolN::new(params.try_into().map_err(|_| count())?)?)
                    })*
                })
            }
        }

        impl fmt::Display for AnyTool {
            /// `model(m1=… m2=… …)`.
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                match self { $(AnyTool::$marker(t) => write!(f, "{t:?}"),)* }
            }
        }
    };
}

crate::for_each_model!(mixed_models);

impl fmt::Display for ModelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ModelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim().to_ascii_lowercase();
        ModelKind::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown model '{}': expected one of {}",
                    crate::display::Clip(&s),
                    generated::MODEL_NAMES.join(", ")
                )
            })
    }
}
