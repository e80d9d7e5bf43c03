//! Linear inequality constraints on the tool parameters, written as a user writes them:
//! `"l1 + l2 >= 0.7"`, `"m1 + m2 <= 0.5"`, `"2*m1 - m2 <= 0.1"`, `"0.5 l1 >= l2 - 0.1"`.
//!
//! Each side is a sum of terms `[±] [number [*]] name`, `name * number`, `name / number` or a
//! number; the comparison is `<=` or `>=`. A constraint is stored as a·p ≤ b over the model's
//! parameters, so `>=` is the same row negated.

use std::fmt;

use crate::validate::{CONSTRAINT_BOUND, CONSTRAINT_COEFFICIENT};
use toolconf_messages::Clip;

/// a·p ≤ b over a model's parameters (in the model's order), with the text it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearConstraint {
    pub coefficients: Vec<f64>,
    pub bound: f64,
    pub text: String,
}

impl LinearConstraint {
    /// a·p − b: positive when `p` violates the constraint.
    pub fn violation(&self, p: &[f64]) -> f64 {
        dot(&self.coefficients, p) - self.bound
    }

    /// The same left side with another bound: `m1 + m2 <= 0.5` at 0.7 is `m1 + m2 <= 0.7`
    /// (for a `>=` constraint, `bound` is the number on its right side too).
    pub fn with_right_side(&self, sense: Sense, right: f64, text: String) -> Self {
        let bound = match sense {
            Sense::AtMost => right,
            Sense::AtLeast => -right,
        };
        Self {
            coefficients: self.coefficients.clone(),
            bound,
            text,
        }
    }
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Which way a constraint points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sense {
    AtMost,
    AtLeast,
}

impl fmt::Display for LinearConstraint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// Parses `text` over the parameter `names`; the error says what is wrong, in words.
pub fn parse_constraint(text: &str, names: &[&str]) -> Result<LinearConstraint, String> {
    let (left, sense, right) = split_comparison(text)?;
    let (a_left, c_left) = parse_side(left, names)?;
    let (a_right, c_right) = parse_side(right, names)?;
    // left ≤ right  ⇔  (a_left − a_right)·p ≤ c_right − c_left.
    let sign = match sense {
        Sense::AtMost => 1.0,
        Sense::AtLeast => -1.0,
    };
    let coefficients: Vec<f64> = a_left
        .iter()
        .zip(&a_right)
        .map(|(l, r)| sign * (l - r))
        .collect();
    if coefficients.iter().all(|&c| c == 0.0) {
        return Err("names no parameter (or its terms cancel)".into());
    }
    for (name, &c) in names.iter().zip(&coefficients) {
        CONSTRAINT_COEFFICIENT
            .check(c)
            .map_err(|why| format!("the coefficient of {name}: {why}"))?;
    }
    let bound = sign * (c_right - c_left);
    CONSTRAINT_BOUND
        .check(bound)
        .map_err(|why| format!("the constant side: {why}"))?;
    Ok(LinearConstraint {
        coefficients,
        bound,
        text: text.trim().to_string(),
    })
}

/// The left side, the comparison and the right side of `text`.
pub fn split_comparison(text: &str) -> Result<(&str, Sense, &str), String> {
    let found: Vec<(usize, &str)> = ["<=", ">=", "==", "<", ">", "="]
        .iter()
        .flat_map(|op| text.match_indices(op).collect::<Vec<_>>())
        .collect();
    let at_most = text.match_indices("<=").count();
    let at_least = text.match_indices(">=").count();
    if at_most + at_least != 1 || found.len() != 3 {
        // One "<=" (or ">=") matches itself, "<" (">") and "=": three hits in all.
        return Err("needs exactly one comparison, <= or >=".into());
    }
    let (op, sense) = if at_most == 1 {
        ("<=", Sense::AtMost)
    } else {
        (">=", Sense::AtLeast)
    };
    let (left, right) = text.split_once(op).expect("counted above");
    Ok((left, sense, right))
}

/// Σ coefficient·name + constant on one side.
fn parse_side(side: &str, names: &[&str]) -> Result<(Vec<f64>, f64), String> {
    let tokens = tokenize(side)?;
    if tokens.is_empty() {
        return Err("a side of the comparison is empty".into());
    }
    let mut coefficients = vec![0.0; names.len()];
    let mut constant = 0.0;
    let mut i = 0;
    while i < tokens.len() {
        let mut sign = 1.0;
        while let Some(Token::Sign(s)) = tokens.get(i) {
            sign *= s;
            i += 1;
        }
        let (factor, name, next) = term(&tokens, i)?;
        match name {
            Some(name) => {
                let k = names.iter().position(|n| *n == name).ok_or_else(|| {
                    format!(
                        "unknown parameter '{}' (parameters: {})",
                        Clip(&name),
                        names.join(", ")
                    )
                })?;
                coefficients[k] += sign * factor;
            }
            None => constant += sign * factor,
        }
        i = next;
        if i < tokens.len() && !matches!(tokens[i], Token::Sign(_)) {
            return Err(format!("expected + or - before '{}'", tokens[i].text()));
        }
    }
    Ok((coefficients, constant))
}

/// One term from `tokens[i]`: (factor, parameter name or None for a constant, next index).
fn term(tokens: &[Token], i: usize) -> Result<(f64, Option<String>, usize), String> {
    match (tokens.get(i), tokens.get(i + 1), tokens.get(i + 2)) {
        (Some(Token::Number(a)), Some(Token::Times), Some(Token::Name(n))) => {
            Ok((*a, Some(n.clone()), i + 3))
        }
        (Some(Token::Number(a)), Some(Token::Name(n)), _) => Ok((*a, Some(n.clone()), i + 2)),
        (Some(Token::Name(n)), Some(Token::Times), Some(Token::Number(a))) => {
            Ok((*a, Some(n.clone()), i + 3))
        }
        (Some(Token::Name(n)), Some(Token::Divide), Some(Token::Number(a))) if *a != 0.0 => {
            Ok((1.0 / a, Some(n.clone()), i + 3))
        }
        (Some(Token::Name(n)), _, _) => Ok((1.0, Some(n.clone()), i + 1)),
        (Some(Token::Number(a)), _, _) => Ok((*a, None, i + 1)),
        (Some(t), _, _) => Err(format!("unexpected '{}'", t.text())),
        (None, _, _) => Err("ends with a sign".into()),
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Token {
    Number(f64),
    Name(String),
    Sign(f64),
    Times,
    Divide,
}

impl Token {
    fn text(&self) -> String {
        match self {
            Token::Number(v) => toolconf_messages::Short(*v).to_string(),
            Token::Name(n) => Clip(n).to_string(),
            Token::Sign(s) => (if *s > 0.0 { "+" } else { "-" }).into(),
            Token::Times => "*".into(),
            Token::Divide => "/".into(),
        }
    }
}

fn tokenize(s: &str) -> Result<Vec<Token>, String> {
    let chars: Vec<char> = s.chars().collect();
    let mut tokens = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c.is_whitespace() {
            i += 1;
        } else if c == '+' || c == '-' {
            tokens.push(Token::Sign(if c == '+' { 1.0 } else { -1.0 }));
            i += 1;
        } else if c == '*' {
            tokens.push(Token::Times);
            i += 1;
        } else if c == '/' {
            tokens.push(Token::Divide);
            i += 1;
        } else if c.is_ascii_digit() || c == '.' {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit()
                    || chars[i] == '.'
                    || ((chars[i] == 'e' || chars[i] == 'E')
                        && chars
                            .get(i + 1)
                            .is_some_and(|d| d.is_ascii_digit() || *d == '-' || *d == '+'))
                    || ((chars[i] == '-' || chars[i] == '+') && matches!(chars[i - 1], 'e' | 'E')))
            {
                i += 1;
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text
                .parse()
                .map_err(|_| format!("'{}' is not a number", Clip(&text)))?;
            if !v.is_finite() {
                return Err(format!("'{}' is not a finite number", Clip(&text)));
            }
            tokens.push(Token::Number(v));
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            tokens.push(Token::Name(chars[start..i].iter().collect()));
        } else {
            return Err(format!("unexpected character '{c}'"));
        }
    }
    Ok(tokens)
}

#[cfg(test)]
mod tests {
    use super::*;

    const NAMES: [&str; 4] = ["m1", "m2", "l1", "l2"];

    fn parse(s: &str) -> LinearConstraint {
        parse_constraint(s, &NAMES).unwrap()
    }

    #[test]
    fn sums_and_senses() {
        let c = parse("l1 + l2 >= 0.7");
        assert_eq!(c.coefficients, vec![0.0, 0.0, -1.0, -1.0]);
        assert_eq!(c.bound, -0.7);
        let c = parse("m1 + m2 <= 0.5");
        assert_eq!(c.coefficients, vec![1.0, 1.0, 0.0, 0.0]);
        assert_eq!(c.bound, 0.5);
    }

    #[test]
    fn coefficients_constants_and_both_sides() {
        let c = parse("2*m1 - m2 <= 0.1");
        assert_eq!(c.coefficients, vec![2.0, -1.0, 0.0, 0.0]);
        assert_eq!(c.bound, 0.1);
        // 0.5 l1 >= l2 - 0.1  ⇔  -0.5 l1 + l2 <= 0.1
        let c = parse("0.5 l1 >= l2 - 0.1");
        assert_eq!(c.coefficients, vec![0.0, 0.0, -0.5, 1.0]);
        assert!((c.bound - 0.1).abs() < 1e-15);
        let c = parse("l1/2 + 1e-1 <= -m2 * 3 + 1.5e0");
        assert_eq!(c.coefficients, vec![0.0, 3.0, 0.5, 0.0]);
        assert!((c.bound - 1.4).abs() < 1e-15);
        assert!(c.violation(&[0.1, 0.1, 0.1, 0.1]) < 0.0);
    }

    #[test]
    fn refusals_say_why() {
        let err = |s: &str| parse_constraint(s, &NAMES).unwrap_err();
        assert!(err("l1 + l3 >= 0.7").contains("unknown parameter 'l3'"));
        assert!(err("l1 + l2").contains("exactly one comparison"));
        assert!(err("l1 <= l2 <= 1").contains("exactly one comparison"));
        assert!(err("l1 == 1").contains("exactly one comparison"));
        assert!(err("l1 < 1").contains("exactly one comparison"));
        assert!(err("l1 l2 <= 1").contains("expected + or -"));
        assert!(err("l1 + <= 1").contains("ends with a sign"));
        assert!(err("l1 - l1 <= 1").contains("names no parameter"));
        assert!(err("1 <= 2").contains("names no parameter"));
        assert!(err("l1 ^ 2 <= 1").contains("unexpected character"));
        assert!(err(" <= 1").contains("empty"));
    }
}
