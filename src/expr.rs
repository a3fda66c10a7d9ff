//! Expressions of the case file in x, y and z: the `height` obstacle's h (contact/height.rs)
//! and the body force `[body_force] expr` (case/body.rs).
//!
//! An expression is parsed once by `evalexpr` ([`Expr::parse`]): its syntax (`^` for powers,
//! `-x^2` = −(x²), scientific notation), every integer literal made a float, only the
//! functions of [`FUNCTIONS`] (evalexpr's own built-ins are off), the constants `pi` and `e`.
//! Which of the variables x, y, z a use allows is checked by the user
//! ([`Expr::unknown_variables`]).

use evalexpr::error::EvalexprResultValue;
use evalexpr::{
    build_operator_tree, Context, DefaultNumericTypes, EvalexprError, EvalexprResult, Node,
    Operator, Value,
};
use std::f64::consts::{E, PI};
use std::fmt;

type V = Value<DefaultNumericTypes>;

/// The functions of an expression: one argument, or two where noted (`f(a, b)`).
pub const FUNCTIONS: [&str; 24] = [
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "ln",
    "log10", "log2", "sqrt", "cbrt", "abs", "pow", "hypot", "floor", "ceil", "min", "max", "sign",
];

/// The variables an expression may read.
pub const VARIABLES: [&str; 3] = ["x", "y", "z"];

/// f64 of a number value.
fn number(v: &V) -> Option<f64> {
    match v {
        Value::Float(f) => Some(*f),
        Value::Int(i) => Some(*i as f64),
        _ => None,
    }
}

/// The one-argument function `name` (without `math::`).
fn one_arg(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "sin" => f64::sin,
        "cos" => f64::cos,
        "tan" => f64::tan,
        "asin" => f64::asin,
        "acos" => f64::acos,
        "atan" => f64::atan,
        "sinh" => f64::sinh,
        "cosh" => f64::cosh,
        "tanh" => f64::tanh,
        "exp" => f64::exp,
        "ln" => f64::ln,
        "log10" => f64::log10,
        "log2" => f64::log2,
        "sqrt" => f64::sqrt,
        "cbrt" => f64::cbrt,
        "abs" => f64::abs,
        "floor" => f64::floor,
        "ceil" => f64::ceil,
        "sign" => |a| if a == 0.0 { 0.0 } else { a.signum() },
        _ => return None,
    })
}

/// The two-argument function `name` (without `math::`).
fn two_arg(name: &str) -> Option<fn(f64, f64) -> f64> {
    Some(match name {
        "atan2" => f64::atan2,
        "pow" => f64::powf,
        "hypot" => f64::hypot,
        "min" => f64::min,
        "max" => f64::max,
        _ => return None,
    })
}

fn call(name: &str, arg: &V) -> EvalexprResultValue<DefaultNumericTypes> {
    let name = name.strip_prefix("math::").unwrap_or(name);
    if let Some(f) = two_arg(name) {
        return match arg {
            Value::Tuple(t) if t.len() == 2 => match (number(&t[0]), number(&t[1])) {
                (Some(a), Some(b)) => Ok(Value::Float(f(a, b))),
                _ => Err(EvalexprError::expected_number(t[0].clone())),
            },
            _ => Err(EvalexprError::expected_tuple(arg.clone())),
        };
    }
    match one_arg(name) {
        Some(f) => number(arg)
            .map(|a| Value::Float(f(a)))
            .ok_or_else(|| EvalexprError::expected_number(arg.clone())),
        None => Err(EvalexprError::FunctionIdentifierNotFound(name.to_string())),
    }
}

/// An expression tree on floats, compiled from evalexpr's tree: the same operations in the
/// same order (so the same values), without evalexpr's value enum, context look-ups and
/// argument vectors (about 20 times faster; the body force is evaluated at every quadrature
/// point of every cell).
enum Code {
    Const(f64),
    Var(usize),
    Neg(Box<Code>),
    Bin(BinOp, Box<Code>, Box<Code>),
    F1(fn(f64) -> f64, Box<Code>),
    F2(fn(f64, f64) -> f64, Box<Code>, Box<Code>),
}

#[derive(Clone, Copy)]
enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
    Pow,
}

impl Code {
    /// The compiled form of `node`; None for what it does not cover (booleans, strings,
    /// assignments, chains, unknown names), which is left to evalexpr.
    fn compile(node: &Node<DefaultNumericTypes>) -> Option<Code> {
        let ch = node.children();
        let sub = |i: usize| Code::compile(&ch[i]).map(Box::new);
        let bin = |op| match ch.len() {
            2 => Some(Code::Bin(op, sub(0)?, sub(1)?)),
            _ => None,
        };
        match node.operator() {
            Operator::RootNode if ch.len() == 1 => Code::compile(&ch[0]),
            Operator::Add => bin(BinOp::Add),
            Operator::Sub => bin(BinOp::Sub),
            Operator::Mul => bin(BinOp::Mul),
            Operator::Div => bin(BinOp::Div),
            Operator::Mod => bin(BinOp::Rem),
            Operator::Exp => bin(BinOp::Pow),
            Operator::Neg if ch.len() == 1 => Some(Code::Neg(sub(0)?)),
            Operator::Const {
                value: Value::Float(f),
            } => Some(Code::Const(*f)),
            Operator::VariableIdentifierRead { identifier } => match identifier.as_str() {
                "pi" => Some(Code::Const(PI)),
                "e" => Some(Code::Const(E)),
                v => VARIABLES.iter().position(|x| *x == v).map(Code::Var),
            },
            Operator::FunctionIdentifier { identifier } if ch.len() == 1 => {
                let name = identifier.strip_prefix("math::").unwrap_or(identifier);
                if let Some(f) = one_arg(name) {
                    return Some(Code::F1(f, sub(0)?));
                }
                let f = two_arg(name)?;
                // The argument: a tuple of two, possibly inside parentheses (root nodes).
                let mut arg = &ch[0];
                while matches!(arg.operator(), Operator::RootNode) && arg.children().len() == 1 {
                    arg = &arg.children()[0];
                }
                let ac = arg.children();
                match arg.operator() {
                    Operator::Tuple if ac.len() == 2 => Some(Code::F2(
                        f,
                        Box::new(Code::compile(&ac[0])?),
                        Box::new(Code::compile(&ac[1])?),
                    )),
                    _ => None,
                }
            }
            _ => None,
        }
    }

    fn eval(&self, p: &[f64; 3]) -> f64 {
        match self {
            Code::Const(c) => *c,
            Code::Var(i) => p[*i],
            Code::Neg(a) => -a.eval(p),
            Code::Bin(op, a, b) => {
                let (a, b) = (a.eval(p), b.eval(p));
                match op {
                    BinOp::Add => a + b,
                    BinOp::Sub => a - b,
                    BinOp::Mul => a * b,
                    BinOp::Div => a / b,
                    BinOp::Rem => a % b,
                    BinOp::Pow => a.powf(b),
                }
            }
            Code::F1(f, a) => f(a.eval(p)),
            Code::F2(f, a, b) => f(a.eval(p), b.eval(p)),
        }
    }
}

/// The variables x, y, z and the constants pi, e of one evaluation; only the functions of
/// [`FUNCTIONS`] (evalexpr's own built-ins are off).
struct Vars {
    x: V,
    y: V,
    z: V,
    pi: V,
    e: V,
}

impl Context for Vars {
    type NumericTypes = DefaultNumericTypes;
    fn get_value(&self, identifier: &str) -> Option<&V> {
        match identifier {
            "x" => Some(&self.x),
            "y" => Some(&self.y),
            "z" => Some(&self.z),
            "pi" => Some(&self.pi),
            "e" => Some(&self.e),
            _ => None,
        }
    }
    fn call_function(
        &self,
        identifier: &str,
        argument: &V,
    ) -> EvalexprResultValue<DefaultNumericTypes> {
        call(identifier, argument)
    }
    fn are_builtin_functions_disabled(&self) -> bool {
        true
    }
    fn set_builtin_functions_disabled(
        &mut self,
        _disabled: bool,
    ) -> EvalexprResult<(), DefaultNumericTypes> {
        Ok(())
    }
}

/// Every integer literal made a float: `1/2` is 0.5, not evalexpr's integer division.
fn floats(node: &mut Node<DefaultNumericTypes>) {
    if let Operator::Const { value } = node.operator_mut() {
        if let Value::Int(i) = value {
            *value = Value::Float(*i as f64);
        }
    }
    for c in node.children_mut() {
        floats(c);
    }
}

/// A parsed expression of x, y, z (see the module's documentation).
pub struct Expr {
    text: String,
    node: Node<DefaultNumericTypes>,
    /// The compiled tree, when it covers the expression (else evalexpr evaluates `node`).
    code: Option<Code>,
    /// The variables read, sorted (constants excluded).
    vars: Vec<String>,
}

impl fmt::Debug for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Expr({:?})", self.text)
    }
}

impl PartialEq for Expr {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

impl Expr {
    /// Parses `text`; the error is a sentence for the user. Checked here: the syntax, only
    /// known functions, no assignment, a number as the result (at x = y = z = 0.5, when only
    /// x, y, z are read). The variables are not checked: see [`Expr::unknown_variables`].
    pub fn parse(text: &str) -> Result<Self, String> {
        if text.trim().is_empty() {
            return Err("the expression is empty".into());
        }
        let mut node =
            build_operator_tree::<DefaultNumericTypes>(text).map_err(|e| e.to_string())?;
        floats(&mut node);
        if node.iter_write_variable_identifiers().next().is_some() {
            return Err("assignments are not allowed: give an expression".into());
        }
        let mut unknown: Vec<&str> = node
            .iter_function_identifiers()
            .filter(|f| !FUNCTIONS.contains(&f.strip_prefix("math::").unwrap_or(f)))
            .collect();
        unknown.dedup();
        if let Some(f) = unknown.first() {
            return Err(format!(
                "unknown function '{f}'; the functions are {}",
                FUNCTIONS.join(", ")
            ));
        }
        let mut vars: Vec<String> = node
            .iter_read_variable_identifiers()
            .filter(|v| *v != "pi" && *v != "e")
            .map(str::to_string)
            .collect();
        vars.sort();
        vars.dedup();
        let code = Code::compile(&node);
        let expr = Expr {
            text: text.to_string(),
            node,
            code,
            vars,
        };
        if expr.unknown_variables(&VARIABLES).is_empty() {
            // The functions give NaN outside their domains, never an error: an error here is
            // a malformed expression (a missing operand, a wrong number of arguments).
            match expr.node.eval_with_context(&context([0.5; 3])) {
                Err(e) => return Err(e.to_string()),
                Ok(v) if number(&v).is_none() => {
                    return Err(format!(
                        "the expression gives {}, not a number",
                        match v {
                            Value::Boolean(_) => "a boolean",
                            Value::String(_) => "a string",
                            Value::Tuple(_) => "a tuple",
                            _ => "no value",
                        }
                    ))
                }
                _ => {}
            }
        }
        Ok(expr)
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The names of the variables the expression reads (sorted; without pi and e).
    pub fn variables(&self) -> &[String] {
        &self.vars
    }

    /// The variables read that are not in `allowed` (sorted).
    pub fn unknown_variables(&self, allowed: &[&str]) -> Vec<&str> {
        self.vars
            .iter()
            .map(String::as_str)
            .filter(|v| !allowed.contains(v))
            .collect()
    }

    /// The value at p = [x, y, z]. NaN where the evaluation fails or gives no number.
    pub fn eval(&self, p: [f64; 3]) -> f64 {
        if let Some(c) = &self.code {
            return c.eval(&p);
        }
        self.eval_tree(p)
    }

    /// [`Expr::eval`] by evalexpr's tree (the reference of the compiled form).
    fn eval_tree(&self, p: [f64; 3]) -> f64 {
        match self.node.eval_with_context(&context(p)) {
            Ok(v) => number(&v).unwrap_or(f64::NAN),
            Err(_) => f64::NAN,
        }
    }
}

fn context(p: [f64; 3]) -> Vars {
    Vars {
        x: Value::Float(p[0]),
        y: Value::Float(p[1]),
        z: Value::Float(p[2]),
        pi: Value::Float(PI),
        e: Value::Float(E),
    }
}

/// `'a', 'b'` for a message.
pub fn quoted(names: &[&str]) -> String {
    names
        .iter()
        .map(|v| format!("'{v}'"))
        .collect::<Vec<_>>()
        .join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_variables_and_their_checks() {
        let e = Expr::parse("x + 2*y - z^2 + pi*0 + 1/2").unwrap();
        assert_eq!(e.variables(), ["x", "y", "z"]);
        assert!((e.eval([1.0, 2.0, 3.0]) - (1.0 + 4.0 - 9.0 + 0.5)).abs() < 1e-15);
        assert!(e.unknown_variables(&VARIABLES).is_empty());
        assert_eq!(e.unknown_variables(&["x", "y"]), ["z"]);
        let e = Expr::parse("t + x").unwrap();
        assert_eq!(e.unknown_variables(&VARIABLES), ["t"]);
        assert!(e.eval([0.0; 3]).is_nan());
        assert!(Expr::parse("max(x)").is_err());
        assert!(Expr::parse("sqrt(x").is_err());
        assert!(Expr::parse("y = 1").unwrap_err().contains("assignments"));
        assert!(Expr::parse("bar(z)").unwrap_err().contains("'bar'"));
        // NaN outside the domain, not an error.
        assert!(Expr::parse("ln(x - 1)").unwrap().eval([0.0; 3]).is_nan());
        assert_eq!(quoted(&["a", "b"]), "'a', 'b'");
    }

    /// The compiled form covers the arithmetic, the functions (also in parentheses, with
    /// math::) and the constants, and gives evalexpr's values bit for bit.
    #[test]
    fn compiled_equals_evalexpr() {
        let texts = [
            "-x^2 + y - z",
            "2^-x + (x - y) * (z + 1) / 3 % 0.7",
            "-6*0.38*1.5*max(0.2025 - x^2, 0)*(0.2025 - 5*x^2)*y*(1 - y) - 2*max(0.2 - x^2, 0)^3",
            "sin(x) + math::cos(y) + tan(z) + asin(x/9) + acos(y/9) + atan(z)",
            "atan2(x, y) + pow(x, 2) + hypot(y, z) + min(x, z) + max((x), (y))",
            "sinh(x) + cosh(y) + tanh(z) + exp(-x) + ln(abs(y) + 1) + log10(3) + log2(8)",
            "sqrt(abs(x)) + cbrt(y) + floor(z) + ceil(x) + sign(y) + sign(0*x) + pi*e",
            "max((x, y))",
            "1/2 + -(-x)",
        ];
        let pts = [
            [0.1, -0.7, 2.5],
            [-1.3, 0.2, 0.0],
            [3.0, 4.0, -5.0],
            [0.0, 0.0, 0.0],
        ];
        for t in texts {
            let e = Expr::parse(t).unwrap();
            assert!(e.code.is_some(), "{t} not compiled");
            for p in pts {
                let (a, b) = (e.eval(p), e.eval_tree(p));
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{t}: {a} {b}"
                );
            }
        }
        // Not covered: left to evalexpr (a boolean is refused by parse, a chain is not).
        let e = Expr::parse("x; y").unwrap();
        assert!(e.code.is_none());
        assert_eq!(e.eval([1.0, 2.0, 3.0]), 2.0);
    }
}
