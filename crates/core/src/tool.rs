//! [`ToolN`]: a tool of one model, its parameters checked once.

use core::fmt;
use core::fmt::Debug;
use core::marker::PhantomData;

use nalgebra::{SMatrix, SVector};

use crate::generated;
use crate::generated::validity::Violation;
use crate::generated::TaskKind;
use crate::Error;

use super::ArmModel;

/// The sensitivities ∂θ/∂U, ∂θ̇/∂U, ∂θ̈/∂U that a task's controller uses (eq. U_dot_deriv), `None`
/// for a term the task does not use. Task 1's ∂θ/∂U
/// is [I O]A⁻¹(∂Ẋ/∂U − B) with ∂Ẋ/∂U = [I; I]; ∂θ̇/∂U is [O I]A⁻¹(∂Ẋ/∂U − B) = I in task 1 and
/// −[I O]A⁻¹B in task 2, as the paper prints it; ∂θ̈/∂U is I in every task (zero jerk in tasks
/// 1–2, [I O](A²∂X/∂U + AB) = I in task 3). The formulas are `derive/tasks.toml`'s.
pub type SensitivitiesN<const N: usize> = generated::TaskSensitivities<N>;

/// One tool of model `M`: its parameters, valid by the model's rule ([`ArmModel::tool_rule`])
/// and within [`crate::validate::TOOL_PARAMETER`].
///
/// The parameters are private so that every `ToolN` has passed [`ToolN::new`].
pub struct ToolN<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> {
    params: SVector<f64, NP>,
    model: PhantomData<M>,
}

// Manual impls: derives would require `M: Clone` etc. through `PhantomData`'s bounds anyway, and
// `M` is a zero-sized marker.
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Clone
    for ToolN<M, N, NX, NP, NZ>
{
    fn clone(&self) -> Self {
        *self
    }
}
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Copy
    for ToolN<M, N, NX, NP, NZ>
{
}
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> PartialEq
    for ToolN<M, N, NX, NP, NZ>
{
    fn eq(&self, other: &Self) -> bool {
        self.params == other.params
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    /// Validates and builds a tool from its parameters in [`ArmModel::parameter_names`] order,
    /// against the model's rule ([`ArmModel::tool_rule`], from its description through the
    /// generated `validity` module): a value outside its parameter's domain is an
    /// [`Error::InvalidParameter`] naming it (domain "> 0": NaN, ±∞, values ≤ 0, and values
    /// outside [`crate::validate::TOOL_PARAMETER`], where the generated arithmetic is not known
    /// to stay finite) or an [`Error::ParameterOutOfDomain`] (any other domain, which the
    /// derivation keeps within ±1e6), a broken constraint across the parameters an
    /// [`Error::ToolConstraint`]. No allocation: tools are checked in bulk.
    pub fn new(params: [f64; NP]) -> Result<Self, Error> {
        let rule = &M::tool_rule();
        // A "> 0" domain within TOOL_PARAMETER first: that also refuses NaN, ±∞ and values ≤ 0,
        // so a domain the rule finds broken below is always another kind.
        let named = M::parameter_names().iter().zip(params).zip(&rule.domains);
        for ((name, value), domain) in named {
            if domain.is_positive() && !crate::validate::TOOL_PARAMETER.contains(value) {
                return Err(Error::InvalidParameter { name, value });
            }
        }
        match rule.check(&params) {
            Ok(()) => {}
            Err(Violation::Domain { index, value }) => {
                return Err(Error::ParameterOutOfDomain {
                    name: M::parameter_names()[index],
                    value,
                    domain: rule.domains[index].rule,
                });
            }
            Err(Violation::Constraint { index, excess }) => {
                let rule = rule.constraints[index].rule;
                return Err(Error::ToolConstraint { rule, excess });
            }
            Err(Violation::Inertia { minor }) => {
                let rule = rule.inertia.map_or("the inertia rule", |i| i.rule);
                return Err(Error::ToolConstraint {
                    rule,
                    excess: -minor,
                });
            }
        }
        Ok(Self {
            params: SVector::from(params),
            model: PhantomData,
        })
    }

    /// The parameter vector p the generated functions take.
    pub fn params(&self) -> SVector<f64, NP> {
        self.params
    }

    /// The model's name.
    pub fn model_name(&self) -> &'static str {
        M::name()
    }

    /// (name, value) of every parameter, in order.
    pub fn named_parameters(&self) -> [(&'static str, f64); NP] {
        core::array::from_fn(|i| (M::parameter_names()[i], self.params[i]))
    }

    /// Ẋ = f(X, U; p).
    pub fn dynamics(&self, x: &SVector<f64, NX>, u: &SVector<f64, N>) -> SVector<f64, NX> {
        M::dynamics(x, u, &self.params)
    }

    /// The robot's own rigid-body dynamics Ẋ = [q̇; q̈], M(q)q̈ + C(q, q̇)q̇ + g(q) = U with U the
    /// joint torques ([`ArmModel::rigid_body_dynamics`]): for a URDF arm the plant without its
    /// joint impedance, for the others the plant itself.
    pub fn rigid_body_dynamics(
        &self,
        x: &SVector<f64, NX>,
        u: &SVector<f64, N>,
    ) -> SVector<f64, NX> {
        M::rigid_body_dynamics(x, u, &self.params)
    }

    /// The tool's tip y(q) in the base frame (m) and its Jacobian ∂y/∂q ([`ArmModel::tip`]),
    /// `None` for a model without a tip.
    pub fn tip(&self, q: &SVector<f64, N>) -> Option<(SVector<f64, 3>, SMatrix<f64, 3, N>)> {
        M::tip(q, &self.params)
    }

    /// A at the equilibrium.
    pub fn state_matrix(&self) -> SMatrix<f64, NX, NX> {
        M::state_matrix(&self.params)
    }

    /// B at the equilibrium.
    pub fn input_matrix(&self) -> SMatrix<f64, NX, N> {
        M::input_matrix(&self.params)
    }

    /// The task's sensitivities.
    pub fn sensitivities(&self, kind: TaskKind) -> SensitivitiesN<N> {
        M::sensitivities(kind, &self.params)
    }
}

impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> Debug
    for ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}({self})", M::name())
    }
}

/// `m1=… m2=… …`: the parameters by name, as error messages name a tool.
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> fmt::Display
    for ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (name, value)) in self.named_parameters().iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{name}={}", crate::display::Short(*value))?;
        }
        Ok(())
    }
}

/// The parameters by name, `{"m1": 0.3, "m2": 0.4, ...}`, as the command line's JSON gives a tool.
#[cfg(feature = "serde")]
impl<M, const N: usize, const NX: usize, const NP: usize, const NZ: usize> serde::Serialize
    for ToolN<M, N, NX, NP, NZ>
where
    M: ArmModel<N, NX, NP, NZ>,
{
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(NP))?;
        for (name, value) in self.named_parameters() {
            map.serialize_entry(name, &value)?;
        }
        map.end()
    }
}
