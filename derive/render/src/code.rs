//! The grammar of the Rust an IR may carry (its closed forms, instruction steps, element
//! accesses and types): what derive/toolconf_derive/rust_printer.py and sequence.py print, and
//! nothing else. An IR is data, whoever wrote it (`make model IR=...`): its code fields are
//! checked against this grammar before any is rendered, so that what reaches the generated
//! crate is arithmetic on named values, never a call, a block, a macro or an item.
//!
//! ```text
//! expression := product (('+' | '-') product)*
//! product    := unary (('*' | '/') unary)*
//! unary      := '-' unary | postfix
//! postfix    := primary ('.' method)*
//! method     := ('sin' | 'cos' | 'tan' | 'exp' | 'ln' | 'abs' | 'sqrt') '(' ')'
//!             | 'powi' '(' ['-'] integer ')' | 'powf' '(' expression ')'
//! primary    := number | name | 'std::f64::consts::E' | '(' expression ')'
//! access     := name ['.' name] '[' integer ']' | name '[' '(' integer ',' integer ')' ']'
//! type       := ['&'] ('SVector<f64,' integer '>' | 'SMatrix<f64,' integer ',' integer '>' | Struct)
//! ```
//!
//! A number is a decimal literal (`3.0`, `1e-3`, `2.5_f64`), a name an ASCII identifier that is
//! no Rust keyword; nesting is bounded ([`MAX_DEPTH`]), so that no IR exhausts the stack.

use crate::escape::is_keyword;

/// The deepest nesting of brackets and unary minus an expression may have (the derivation's
/// deepest is a few dozen).
pub const MAX_DEPTH: usize = 200;

#[derive(Debug, Clone, PartialEq)]
enum Token<'a> {
    Name(&'a str),
    Number(&'a str),
    Integer(&'a str),
    Punct(&'static str),
}

const PUNCTS: [&str; 14] = [
    "::", "+", "-", "*", "/", "(", ")", "[", "]", ",", ".", "&", "<", ">",
];

fn tokens(text: &str) -> Result<Vec<Token<'_>>, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if b == b' ' {
            i += 1;
        } else if b.is_ascii_alphabetic() || b == b'_' {
            let end = i + bytes[i..]
                .iter()
                .take_while(|b| b.is_ascii_alphanumeric() || **b == b'_')
                .count();
            out.push(Token::Name(&text[i..end]));
            i = end;
        } else if b.is_ascii_digit() {
            let end = number_end(bytes, i);
            let literal = &text[i..end];
            let integer = literal.bytes().all(|b| b.is_ascii_digit());
            out.push(if integer {
                Token::Integer(literal)
            } else {
                Token::Number(literal)
            });
            i = end;
        } else if let Some(p) = PUNCTS.iter().find(|p| text[i..].starts_with(**p)) {
            out.push(Token::Punct(p));
            i += p.len();
        } else {
            let c = text[i..].chars().next().unwrap_or('?');
            return Err(format!(
                "'{}' is not part of the IR's code grammar",
                c.escape_debug()
            ));
        }
    }
    Ok(out)
}

/// The end of a decimal literal starting at `i`: digits, an optional fraction, an optional
/// exponent, an optional `_f64`.
fn number_end(bytes: &[u8], mut i: usize) -> usize {
    let digits = |i: usize| i + bytes[i..].iter().take_while(|b| b.is_ascii_digit()).count();
    i = digits(i);
    if bytes.get(i) == Some(&b'.') && bytes.get(i + 1).is_some_and(u8::is_ascii_digit) {
        i = digits(i + 1);
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        let sign = usize::from(matches!(bytes.get(i + 1), Some(b'+' | b'-')));
        if bytes.get(i + 1 + sign).is_some_and(u8::is_ascii_digit) {
            i = digits(i + 1 + sign);
        }
    }
    if bytes[i..].starts_with(b"_f64") {
        i += 4;
    }
    i
}

struct Parser<'a> {
    tokens: Vec<Token<'a>>,
    at: usize,
    depth: usize,
}

const METHODS: [&str; 7] = ["sin", "cos", "tan", "exp", "ln", "abs", "sqrt"];

impl<'a> Parser<'a> {
    fn new(text: &'a str) -> Result<Self, String> {
        Ok(Self {
            tokens: tokens(text)?,
            at: 0,
            depth: 0,
        })
    }

    fn peek(&self) -> Option<&Token<'a>> {
        self.tokens.get(self.at)
    }

    fn eat(&mut self, punct: &str) -> bool {
        let found = matches!(self.peek(), Some(Token::Punct(p)) if *p == punct);
        self.at += usize::from(found);
        found
    }

    fn expect(&mut self, punct: &str) -> Result<(), String> {
        if self.eat(punct) {
            Ok(())
        } else {
            Err(format!("'{punct}' expected at token {}", self.at + 1))
        }
    }

    fn name(&mut self) -> Result<&'a str, String> {
        match self.peek() {
            Some(Token::Name(n)) if !is_keyword(n) => {
                let n = *n;
                self.at += 1;
                Ok(n)
            }
            Some(Token::Name(n)) => Err(format!("'{n}' is a Rust keyword")),
            _ => Err(format!("a name expected at token {}", self.at + 1)),
        }
    }

    fn integer(&mut self) -> Result<(), String> {
        match self.peek() {
            Some(Token::Integer(_)) => {
                self.at += 1;
                Ok(())
            }
            _ => Err(format!("an integer expected at token {}", self.at + 1)),
        }
    }

    fn end(&self) -> Result<(), String> {
        match self.at == self.tokens.len() {
            true => Ok(()),
            false => Err(format!("unexpected text at token {}", self.at + 1)),
        }
    }

    fn nested<T>(&mut self, f: impl FnOnce(&mut Self) -> Result<T, String>) -> Result<T, String> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(format!("nested more than {MAX_DEPTH} deep"));
        }
        let out = f(self);
        self.depth -= 1;
        out
    }

    fn expression(&mut self) -> Result<(), String> {
        self.product()?;
        while self.eat("+") || self.eat("-") {
            self.product()?;
        }
        Ok(())
    }

    fn product(&mut self) -> Result<(), String> {
        self.unary()?;
        while self.eat("*") || self.eat("/") {
            self.unary()?;
        }
        Ok(())
    }

    fn unary(&mut self) -> Result<(), String> {
        if self.eat("-") {
            return self.nested(Self::unary);
        }
        self.primary()?;
        while self.eat(".") {
            self.method()?;
        }
        Ok(())
    }

    fn method(&mut self) -> Result<(), String> {
        let name = self.name()?;
        self.expect("(")?;
        match name {
            m if METHODS.contains(&m) => {}
            "powi" => {
                self.eat("-");
                self.integer()?;
            }
            "powf" => self.nested(Self::expression)?,
            other => return Err(format!("'.{other}(…)' is not a method of the IR's code")),
        }
        self.expect(")")
    }

    fn primary(&mut self) -> Result<(), String> {
        match self.peek() {
            Some(Token::Number(_) | Token::Integer(_)) => {
                self.at += 1;
                Ok(())
            }
            Some(Token::Name("std")) => {
                for part in ["std", "f64", "consts", "E"] {
                    if part != "std" {
                        self.expect("::")?;
                    }
                    match self.peek() {
                        Some(Token::Name(n)) if *n == part => self.at += 1,
                        _ => {
                            return Err(
                                "the one path the IR's code has is std::f64::consts::E".into()
                            )
                        }
                    }
                }
                Ok(())
            }
            Some(Token::Name(_)) => self.name().map(drop),
            Some(Token::Punct("(")) => {
                self.at += 1;
                self.nested(Self::expression)?;
                self.expect(")")
            }
            _ => Err(format!(
                "a number, a name or '(' expected at token {}",
                self.at + 1
            )),
        }
    }

    fn access(&mut self) -> Result<(), String> {
        self.name()?;
        if self.eat(".") {
            self.name()?;
        }
        self.expect("[")?;
        if self.eat("(") {
            self.integer()?;
            self.expect(",")?;
            self.integer()?;
            self.expect(")")?;
        } else {
            self.integer()?;
        }
        self.expect("]")
    }

    fn rust_type(&mut self) -> Result<(), String> {
        self.eat("&");
        let name = self.name()?;
        let dimensions = match name {
            "SVector" => 1,
            "SMatrix" => 2,
            _ if camel_case(name) => return Ok(()),
            other => return Err(format!("'{other}' is not a type of the IR's code")),
        };
        self.expect("<")?;
        if self.name()? != "f64" {
            return Err("a vector or matrix of f64 expected".into());
        }
        for _ in 0..dimensions {
            self.expect(",")?;
            self.integer()?;
        }
        self.expect(">")
    }
}

/// A struct's name: an ASCII upper-case letter, then letters and digits.
pub fn camel_case(name: &str) -> bool {
    name.bytes().next().is_some_and(|b| b.is_ascii_uppercase())
        && name.bytes().all(|b| b.is_ascii_alphanumeric())
}

fn whole<'a>(
    text: &'a str,
    rule: impl FnOnce(&mut Parser<'a>) -> Result<(), String>,
) -> Result<(), String> {
    let mut p = Parser::new(text)?;
    if p.tokens.is_empty() {
        return Err("empty".into());
    }
    rule(&mut p)?;
    p.end()
}

/// Why `text` is not an expression of the grammar (module docs), if it is not.
pub fn expression(text: &str) -> Result<(), String> {
    whole(text, Parser::expression)
}

/// Why `text` is not an element access (`x[0]`, `p[(1, 2)]`, `coefficients.k[3]`).
pub fn access(text: &str) -> Result<(), String> {
    whole(text, Parser::access)
}

/// Why `text` is not an assignment's target: a name or an element access.
pub fn target(text: &str) -> Result<(), String> {
    whole(text, |p| match p.tokens.len() {
        1 => p.name().map(drop),
        _ => p.access(),
    })
}

/// Why `text` is not a type of the grammar.
pub fn rust_type(text: &str) -> Result<(), String> {
    whole(text, Parser::rust_type)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_derivations_code_is_in_the_grammar() {
        for ok in [
            "-(3.0 / 2.0) * g * s5",
            "l2.powi(2) * m2",
            "(-0.0031274395439999996) + s6_3",
            "2.0_f64.sin() * x.sqrt().powf(1.5)",
            "t93 * (t103 * (2.0 * t0 * t131 * t25) - t123)",
            "1e-3 + 2.5E+4",
            "std::f64::consts::E",
            "-PI / 2.0",
            "x.powi(-2)",
        ] {
            assert_eq!(expression(ok), Ok(()), "{ok}");
        }
        for ok in ["x[0]", "p_theta_ddot[(6, 6)]", "coefficients.k[3]"] {
            assert_eq!(access(ok), Ok(()), "{ok}");
            assert_eq!(target(ok), Ok(()), "{ok}");
        }
        assert_eq!(target("w104"), Ok(()));
        for ok in [
            "SVector<f64, 4>",
            "&SMatrix<f64, 12, 12>",
            "&DynamicsCoefficients",
        ] {
            assert_eq!(rust_type(ok), Ok(()), "{ok}");
        }
    }

    #[test]
    fn code_outside_the_grammar_is_refused() {
        for bad in [
            "",
            "x; std::process::exit(1)",
            "{ 1.0 }",
            "f(x)",
            "x.to_string()",
            "std::process::abort()",
            "unsafe { *p }",
            "println!(\"x\")",
            "x as u8",
            "\"text\"",
            "a\nb",
            "x[0]",
            "#[used] x",
            "|x| x",
            "1.0 +",
            "loop",
        ] {
            assert!(expression(bad).is_err(), "{bad}");
        }
        assert!(expression(&format!("{}1.0{}", "(".repeat(500), ")".repeat(500))).is_err());
        assert!(expression(&"-".repeat(500)).is_err());
        for bad in ["x[0]; y", "x", "x[a]", "x.k.l[0]"] {
            assert!(access(bad).is_err(), "{bad}");
        }
        for bad in ["Vec<u8>", "SVector<u8, 1>", "&&X", "fn()", "snake"] {
            assert!(rust_type(bad).is_err(), "{bad}");
        }
    }
}
