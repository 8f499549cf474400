//! The Structured Text of PLCopen bodies, conditions and actions: a lexer and a parser
//! for the statements and expressions that a Boolean control program uses.
//!
//! Statements: `x := e;`, `IF … THEN … ELSIF … ELSE … END_IF;` and function-block calls
//! with named inputs (`trig(CLK := x);`). Expressions: `OR`, `XOR`, `AND` (`&`), `NOT`,
//! comparisons, parentheses, `TRUE`/`FALSE`, integer and `T#…` time literals, variables
//! and `a.b` members. `(* *)` and `//` comments and `{ }` pragmas are skipped.
//! Anything else (`CASE`, loops, arithmetic) is refused with its line and column, never
//! skipped.

/// A position in the ST text, 1-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub(crate) struct Pos {
    pub(crate) line: usize,
    pub(crate) column: usize,
}

/// A binary operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum BinOp {
    Or,
    Xor,
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
}

/// An expression.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum StExpr {
    Bool(bool),
    Int(i64),
    /// A `T#…` literal, in milliseconds.
    Time(u64),
    /// `a` or `a.b`, as written.
    Var {
        path: Vec<String>,
        at: Pos,
    },
    Not(Box<StExpr>),
    Bin(BinOp, Box<StExpr>, Box<StExpr>),
    /// The rising or falling edge of a variable: an LD edge contact or an `R_TRIG`/
    /// `F_TRIG` output (never written in ST itself).
    Edge {
        rising: bool,
        path: Vec<String>,
        at: Pos,
    },
}

/// A statement.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Stmt {
    Assign {
        target: Vec<String>,
        value: StExpr,
        at: Pos,
    },
    If {
        branches: Vec<(StExpr, Vec<Stmt>)>,
        otherwise: Vec<Stmt>,
    },
    Call {
        instance: String,
        args: Vec<(String, StExpr)>,
        at: Pos,
    },
}

/// A syntax error or an unsupported construct, with its position in the ST text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct StError {
    pub(crate) message: String,
    pub(crate) at: Pos,
}

#[derive(Clone, Debug, PartialEq, Eq)]
enum Tok {
    Id(String),
    Int(i64),
    Time(u64),
    Assign,
    Semi,
    Colon,
    Comma,
    Dot,
    Open,
    Close,
    Op(&'static str),
    End,
}

impl Tok {
    fn describe(&self) -> String {
        match self {
            Tok::Id(s) => format!("`{s}`"),
            Tok::Int(n) => format!("`{n}`"),
            Tok::Time(ms) => format!("`T#{ms}ms`"),
            Tok::Assign => "`:=`".into(),
            Tok::Semi => "`;`".into(),
            Tok::Colon => "`:`".into(),
            Tok::Comma => "`,`".into(),
            Tok::Dot => "`.`".into(),
            Tok::Open => "`(`".into(),
            Tok::Close => "`)`".into(),
            Tok::Op(o) => format!("`{o}`"),
            Tok::End => "the end of the text".into(),
        }
    }

    fn is_kw(&self, kw: &str) -> bool {
        matches!(self, Tok::Id(s) if s.eq_ignore_ascii_case(kw))
    }
}

const UNSUPPORTED: &[&str] = &[
    "CASE", "FOR", "WHILE", "REPEAT", "RETURN", "EXIT", "MOD", "JMP",
];

struct Lexer {
    chars: Vec<char>,
    i: usize,
    line: usize,
    column: usize,
}

impl Lexer {
    fn peek(&self, k: usize) -> Option<char> {
        self.chars.get(self.i + k).copied()
    }

    fn bump(&mut self) {
        if let Some(c) = self.peek(0) {
            self.i += 1;
            if c == '\n' {
                self.line += 1;
                self.column = 1;
            } else {
                self.column += 1;
            }
        }
    }

    fn pos(&self) -> Pos {
        Pos {
            line: self.line,
            column: self.column,
        }
    }

    fn skip_until(&mut self, end: &str, at: Pos) -> Result<(), StError> {
        let end: Vec<char> = end.chars().collect();
        loop {
            if self.i >= self.chars.len() {
                return Err(StError {
                    message: format!(
                        "a comment or pragma not closed by `{}`",
                        end.iter().collect::<String>()
                    ),
                    at,
                });
            }
            if self.chars[self.i..].starts_with(&end) {
                for _ in 0..end.len() {
                    self.bump();
                }
                return Ok(());
            }
            self.bump();
        }
    }

    fn word(&mut self) -> String {
        let mut s = String::new();
        while let Some(c) = self.peek(0) {
            if c.is_ascii_alphanumeric() || c == '_' {
                s.push(c);
                self.bump();
            } else {
                break;
            }
        }
        s
    }

    /// The rest of a `T#` literal: `1s500ms`, `2.5s`, `300ms`, `1h_2m`.
    fn time(&mut self, at: Pos) -> Result<u64, StError> {
        let mut text = String::new();
        while let Some(c) = self.peek(0) {
            if c.is_ascii_alphanumeric() || c == '_' || c == '.' {
                text.push(c);
                self.bump();
            } else {
                break;
            }
        }
        parse_duration(&text).ok_or_else(|| StError {
            message: format!("`T#{text}` is not a duration (write e.g. T#2s or T#1s500ms)"),
            at,
        })
    }

    fn tokens(mut self) -> Result<Vec<(Tok, Pos)>, StError> {
        let mut out = Vec::new();
        while let Some(c) = self.peek(0) {
            let at = self.pos();
            if c.is_whitespace() {
                self.bump();
                continue;
            }
            if c == '(' && self.peek(1) == Some('*') {
                self.bump();
                self.bump();
                self.skip_until("*)", at)?;
                continue;
            }
            if c == '/' && self.peek(1) == Some('/') {
                while self.peek(0).is_some_and(|c| c != '\n') {
                    self.bump();
                }
                continue;
            }
            if c == '{' {
                self.bump();
                self.skip_until("}", at)?;
                continue;
            }
            if c.is_ascii_alphabetic() || c == '_' {
                let w = self.word();
                if self.peek(0) == Some('#') {
                    self.bump();
                    let upper = w.to_ascii_uppercase();
                    if upper == "T" || upper == "TIME" {
                        let ms = self.time(at)?;
                        out.push((Tok::Time(ms), at));
                        continue;
                    }
                    if upper == "BOOL" {
                        let v = self.word();
                        out.push((Tok::Id(v), at));
                        continue;
                    }
                    return Err(StError {
                        message: format!("the typed literal `{w}#…` is not supported"),
                        at,
                    });
                }
                out.push((Tok::Id(w), at));
                continue;
            }
            if c.is_ascii_digit() {
                let w = self.word();
                let digits: String = w.chars().filter(|c| *c != '_').collect();
                let n = digits.parse::<i64>().map_err(|_| StError {
                    message: format!("`{w}` is not an integer literal"),
                    at,
                })?;
                out.push((Tok::Int(n), at));
                continue;
            }
            let two: String = [Some(c), self.peek(1)].iter().flatten().collect();
            let tok = match two.as_str() {
                ":=" => Some(Tok::Assign),
                "<>" => Some(Tok::Op("<>")),
                "<=" => Some(Tok::Op("<=")),
                ">=" => Some(Tok::Op(">=")),
                "=>" => Some(Tok::Op("=>")),
                _ => None,
            };
            if let Some(t) = tok {
                self.bump();
                self.bump();
                out.push((t, at));
                continue;
            }
            let tok = match c {
                ';' => Tok::Semi,
                ':' => Tok::Colon,
                ',' => Tok::Comma,
                '.' => Tok::Dot,
                '(' => Tok::Open,
                ')' => Tok::Close,
                '&' => Tok::Op("&"),
                '=' => Tok::Op("="),
                '<' => Tok::Op("<"),
                '>' => Tok::Op(">"),
                '+' => Tok::Op("+"),
                '-' => Tok::Op("-"),
                '*' => Tok::Op("*"),
                '/' => Tok::Op("/"),
                _ => {
                    return Err(StError {
                        message: format!("unexpected character `{c}`"),
                        at,
                    });
                }
            };
            self.bump();
            out.push((tok, at));
        }
        out.push((Tok::End, self.pos()));
        Ok(out)
    }
}

/// Milliseconds of an IEC duration without its `T#` (`1s500ms`, `2.5s`, `1h_30m`).
pub(crate) fn parse_duration(text: &str) -> Option<u64> {
    let t = text.to_ascii_lowercase().replace('_', "");
    if t.is_empty() {
        return None;
    }
    let mut total = 0f64;
    let mut rest = t.as_str();
    while !rest.is_empty() {
        let n_end = rest.find(|c: char| !(c.is_ascii_digit() || c == '.'))?;
        let n: f64 = rest[..n_end].parse().ok()?;
        rest = &rest[n_end..];
        let (unit, len) = if rest.starts_with("ms") {
            (1.0, 2)
        } else if rest.starts_with('d') {
            (86_400_000.0, 1)
        } else if rest.starts_with('h') {
            (3_600_000.0, 1)
        } else if rest.starts_with('m') {
            (60_000.0, 1)
        } else if rest.starts_with('s') {
            (1000.0, 1)
        } else {
            return None;
        };
        total += n * unit;
        rest = &rest[len..];
    }
    (total.is_finite() && total >= 0.0 && total.fract() == 0.0).then_some(total as u64)
}

/// Writes milliseconds as an IEC duration literal (`T#1500ms`).
pub(crate) fn write_duration(ms: u64) -> String {
    format!("T#{ms}ms")
}

struct Parser {
    toks: Vec<(Tok, Pos)>,
    i: usize,
}

impl Parser {
    fn new(text: &str) -> Result<Self, StError> {
        let lexer = Lexer {
            chars: text.chars().collect(),
            i: 0,
            line: 1,
            column: 1,
        };
        Ok(Self {
            toks: lexer.tokens()?,
            i: 0,
        })
    }

    fn peek(&self) -> &(Tok, Pos) {
        let last = self.toks.len() - 1;
        &self.toks[self.i.min(last)]
    }

    fn next(&mut self) -> (Tok, Pos) {
        let t = self.peek().clone();
        if self.i < self.toks.len() - 1 {
            self.i += 1;
        }
        t
    }

    fn fail<T>(&self, what: &str) -> Result<T, StError> {
        let (tok, at) = self.peek();
        Err(StError {
            message: format!("expected {what}, found {}", tok.describe()),
            at: *at,
        })
    }

    fn expect(&mut self, tok: &Tok, what: &str) -> Result<Pos, StError> {
        if &self.peek().0 == tok {
            Ok(self.next().1)
        } else {
            self.fail(what)
        }
    }

    fn expect_kw(&mut self, kw: &str) -> Result<Pos, StError> {
        if self.peek().0.is_kw(kw) {
            Ok(self.next().1)
        } else {
            self.fail(&format!("`{kw}`"))
        }
    }

    fn statements(&mut self, ends: &[&str]) -> Result<Vec<Stmt>, StError> {
        let mut out = Vec::new();
        loop {
            let (tok, at) = self.peek().clone();
            if tok == Tok::End || ends.iter().any(|e| tok.is_kw(e)) {
                return Ok(out);
            }
            if tok == Tok::Semi {
                self.next();
                continue;
            }
            if let Tok::Id(w) = &tok {
                if let Some(kw) = UNSUPPORTED.iter().find(|k| w.eq_ignore_ascii_case(k)) {
                    return Err(StError {
                        message: format!(
                            "the ST statement `{kw}` is not supported (Boolean control programs use assignments, IF and function-block calls)"
                        ),
                        at,
                    });
                }
                if w.eq_ignore_ascii_case("IF") {
                    out.push(self.if_statement()?);
                    continue;
                }
            }
            out.push(self.simple_statement()?);
        }
    }

    fn if_statement(&mut self) -> Result<Stmt, StError> {
        self.expect_kw("IF")?;
        let mut branches = Vec::new();
        let mut otherwise = Vec::new();
        loop {
            let cond = self.expr()?;
            self.expect_kw("THEN")?;
            let body = self.statements(&["ELSIF", "ELSE", "END_IF"])?;
            branches.push((cond, body));
            let (tok, _) = self.peek().clone();
            if tok.is_kw("ELSIF") {
                self.next();
                continue;
            }
            if tok.is_kw("ELSE") {
                self.next();
                otherwise = self.statements(&["END_IF"])?;
            }
            self.expect_kw("END_IF")?;
            if self.peek().0 == Tok::Semi {
                self.next();
            }
            return Ok(Stmt::If {
                branches,
                otherwise,
            });
        }
    }

    fn path(&mut self) -> Result<(Vec<String>, Pos), StError> {
        let (tok, at) = self.next();
        let Tok::Id(first) = tok else {
            self.i -= 1;
            return self.fail("a variable name");
        };
        let mut path = vec![first];
        while self.peek().0 == Tok::Dot {
            self.next();
            match self.next() {
                (Tok::Id(m), _) => path.push(m),
                _ => {
                    self.i -= 1;
                    return self.fail("a member name after `.`");
                }
            }
        }
        Ok((path, at))
    }

    fn simple_statement(&mut self) -> Result<Stmt, StError> {
        let (target, at) = self.path()?;
        match self.peek().0 {
            Tok::Assign => {
                self.next();
                let value = self.expr()?;
                self.expect(&Tok::Semi, "`;` after the assignment")?;
                Ok(Stmt::Assign { target, value, at })
            }
            Tok::Open if target.len() == 1 => {
                self.next();
                let mut args = Vec::new();
                while self.peek().0 != Tok::Close {
                    let (name, name_at) = self.path()?;
                    if name.len() != 1 {
                        return Err(StError {
                            message: "a function-block input is a plain name".into(),
                            at: name_at,
                        });
                    }
                    if self.peek().0 == Tok::Op("=>") {
                        return Err(StError {
                            message: "output assignments `=>` in a call are not supported: read the instance's output as `inst.Q`".into(),
                            at: self.peek().1,
                        });
                    }
                    self.expect(&Tok::Assign, "`:=` after the input name")?;
                    let value = self.expr()?;
                    args.push((name.concat(), value));
                    if self.peek().0 == Tok::Comma {
                        self.next();
                    } else if self.peek().0 != Tok::Close {
                        return self.fail("`,` or `)`");
                    }
                }
                self.next();
                self.expect(&Tok::Semi, "`;` after the call")?;
                Ok(Stmt::Call {
                    instance: target.concat(),
                    args,
                    at,
                })
            }
            _ => self.fail("`:=` or a call"),
        }
    }

    fn expr(&mut self) -> Result<StExpr, StError> {
        self.binary(0)
    }

    fn binary(&mut self, level: usize) -> Result<StExpr, StError> {
        // Levels, loosest first: OR, XOR, AND, comparison.
        if level == 4 {
            return self.unary();
        }
        let mut left = self.binary(level + 1)?;
        loop {
            let (tok, _) = self.peek().clone();
            let op = match (level, &tok) {
                (0, t) if t.is_kw("OR") => BinOp::Or,
                (1, t) if t.is_kw("XOR") => BinOp::Xor,
                (2, t) if t.is_kw("AND") || *t == Tok::Op("&") => BinOp::And,
                (3, Tok::Op("=")) => BinOp::Eq,
                (3, Tok::Op("<>")) => BinOp::Ne,
                (3, Tok::Op("<")) => BinOp::Lt,
                (3, Tok::Op("<=")) => BinOp::Le,
                (3, Tok::Op(">")) => BinOp::Gt,
                (3, Tok::Op(">=")) => BinOp::Ge,
                _ => return Ok(left),
            };
            self.next();
            let right = self.binary(level + 1)?;
            left = StExpr::Bin(op, Box::new(left), Box::new(right));
        }
    }

    fn unary(&mut self) -> Result<StExpr, StError> {
        let (tok, at) = self.peek().clone();
        if tok.is_kw("NOT") {
            self.next();
            return Ok(StExpr::Not(Box::new(self.unary()?)));
        }
        let e = match tok {
            Tok::Open => {
                self.next();
                let e = self.expr()?;
                self.expect(&Tok::Close, "`)`")?;
                e
            }
            Tok::Int(n) => {
                self.next();
                StExpr::Int(n)
            }
            Tok::Time(ms) => {
                self.next();
                StExpr::Time(ms)
            }
            Tok::Id(ref w) if w.eq_ignore_ascii_case("TRUE") => {
                self.next();
                StExpr::Bool(true)
            }
            Tok::Id(ref w) if w.eq_ignore_ascii_case("FALSE") => {
                self.next();
                StExpr::Bool(false)
            }
            Tok::Id(_) => {
                let (path, at) = self.path()?;
                if self.peek().0 == Tok::Open {
                    return Err(StError {
                        message: format!(
                            "the function call `{}(…)` is not supported in an expression",
                            path.join(".")
                        ),
                        at,
                    });
                }
                StExpr::Var { path, at }
            }
            Tok::Op(op @ ("+" | "-" | "*" | "/")) => {
                return Err(StError {
                    message: format!(
                        "arithmetic (`{op}`) is not supported in a Boolean control program"
                    ),
                    at,
                });
            }
            _ => return self.fail("an expression"),
        };
        if let Tok::Op(op @ ("+" | "-" | "*" | "/")) = self.peek().0 {
            return Err(StError {
                message: format!(
                    "arithmetic (`{op}`) is not supported in a Boolean control program"
                ),
                at: self.peek().1,
            });
        }
        Ok(e)
    }
}

/// Parses a statement list (an ST body or an action).
pub(crate) fn parse_statements(text: &str) -> Result<Vec<Stmt>, StError> {
    let mut p = Parser::new(text)?;
    let out = p.statements(&[])?;
    if p.peek().0 != Tok::End {
        return p.fail("a statement");
    }
    Ok(out)
}

/// Parses a transition condition: an expression, optionally written `:= e;`.
pub(crate) fn parse_condition(text: &str) -> Result<StExpr, StError> {
    let mut p = Parser::new(text)?;
    if p.peek().0 == Tok::Assign {
        p.next();
    }
    let e = p.expr()?;
    if p.peek().0 == Tok::Semi {
        p.next();
    }
    if p.peek().0 != Tok::End {
        return p.fail("the end of the condition");
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_as_iec_writes_them() {
        assert_eq!(parse_duration("2s"), Some(2000));
        assert_eq!(parse_duration("1s500ms"), Some(1500));
        assert_eq!(parse_duration("2.5s"), Some(2500));
        assert_eq!(parse_duration("1h_30m"), Some(5_400_000));
        assert_eq!(parse_duration("300MS"), Some(300));
        assert_eq!(parse_duration("2x"), None);
        assert_eq!(parse_duration(""), None);
        assert_eq!(parse_duration("0.0005s"), None);
    }

    #[test]
    fn precedence_is_not_and_xor_or() {
        let e = parse_condition("a OR b AND NOT c XOR d").unwrap();
        let StExpr::Bin(BinOp::Or, _, right) = e else {
            panic!("OR is loosest: {e:?}")
        };
        assert!(matches!(*right, StExpr::Bin(BinOp::Xor, _, _)));
    }

    #[test]
    fn unsupported_constructs_are_named_with_their_position() {
        let e = parse_statements("x := TRUE;\n  FOR i := 1 TO 3 DO END_FOR;").unwrap_err();
        assert_eq!(e.at, Pos { line: 2, column: 3 });
        assert!(e.message.contains("FOR"), "{}", e.message);
        let e = parse_statements("n := n + 1;").unwrap_err();
        assert!(e.message.contains("arithmetic"), "{}", e.message);
        let e = parse_statements("x := TRUE (* open").unwrap_err();
        assert!(e.message.contains("not closed"), "{}", e.message);
    }

    #[test]
    fn statements_with_if_and_calls() {
        let s = parse_statements(
            "(* c *) t(CLK := C0); IF t.Q THEN m := TRUE; ELSIF b THEN m := FALSE; ELSE ; END_IF;",
        )
        .unwrap();
        assert_eq!(s.len(), 2);
        assert!(
            matches!(&s[0], Stmt::Call { instance, args, .. } if instance == "t" && args.len() == 1)
        );
        assert!(matches!(&s[1], Stmt::If { branches, .. } if branches.len() == 2));
    }
}
