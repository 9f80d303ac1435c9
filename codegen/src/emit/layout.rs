//! Line breaking of long generated statements, as prettyplease breaks them.
//!
//! The statements of generated functions are printed as text (`text.rs`); the ones that do not
//! fit on a line are laid out here instead of going through syn and prettyplease one by one
//! (which took most of the emission time of large models). The statements form a small
//! language — `let NAME = EXPR;` and `PLACE[INDEX] = EXPR;` with sums, differences, products,
//! quotients, negation, parentheses, identifiers, `p.FIELD` and float literals — which is
//! parsed here with Rust's precedences and printed with the boxes and breaks prettyplease uses
//! for each of these constructs, by Oppen's line-breaking algorithm (the one prettyplease
//! implements): a box is broken if its contents up to the next break outside it do not fit in
//! the rest of the line; a break of a broken inconsistent box is taken if the text up to the
//! next break does not fit; a broken consistent box takes all its breaks. Anything outside the
//! small language gives `None` (the caller formats it with prettyplease). The tests of
//! `text.rs` compare the result with prettyplease on every statement of several models.

/// prettyplease's line width (see `text.rs`).
const MARGIN: isize = 89;
/// prettyplease's least space after the indentation.
const MIN_SPACE: isize = 60;
/// prettyplease's indentation step.
const INDENT: isize = 4;
/// The size of a hard break (a newline that is always taken).
const INFINITY: isize = 0xffff;

/// A token of the statement text.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Lex<'a> {
    Ident(&'a str),
    Number(&'a str),
    Punct(u8),
}

fn lex(s: &str) -> Option<Vec<Lex<'_>>> {
    let b = s.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c == b' ' {
            i += 1;
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push(Lex::Ident(&s[start..i]));
        } else if c.is_ascii_digit() {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                i += 1;
                if i < b.len() && (b[i] == b'-' || b[i] == b'+') {
                    i += 1;
                }
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            out.push(Lex::Number(&s[start..i]));
        } else if b"+-*/()[].,=;".contains(&c) {
            out.push(Lex::Punct(c));
            i += 1;
        } else {
            return None;
        }
    }
    Some(out)
}

/// The syntax tree of an expression of the small language.
enum Expr<'a> {
    /// An identifier or a literal.
    Word(&'a str),
    /// `base.member`.
    Field(&'a str, &'a str),
    /// `-expr`.
    Neg(Box<Expr<'a>>),
    /// `(expr)`.
    Paren(Box<Expr<'a>>),
    /// `left op right`.
    Binary(Box<Expr<'a>>, u8, Box<Expr<'a>>),
}

/// A statement of the small language.
enum Stmt<'a> {
    /// `let NAME = EXPR;`
    Let(&'a str, Expr<'a>),
    /// `PLACE[i] = EXPR;` or `PLACE[(i, j)] = EXPR;`
    Store(&'a str, Vec<&'a str>, Expr<'a>),
}

struct Parser<'a> {
    toks: Vec<Lex<'a>>,
    at: usize,
}

impl<'a> Parser<'a> {
    fn peek(&self) -> Option<Lex<'a>> {
        self.toks.get(self.at).copied()
    }

    fn next(&mut self) -> Option<Lex<'a>> {
        let t = self.peek();
        self.at += 1;
        t
    }

    fn eat(&mut self, c: u8) -> Option<()> {
        (self.next()? == Lex::Punct(c)).then_some(())
    }

    fn stmt(&mut self) -> Option<Stmt<'a>> {
        let Lex::Ident(first) = self.next()? else {
            return None;
        };
        let s = if first == "let" {
            let Lex::Ident(name) = self.next()? else {
                return None;
            };
            self.eat(b'=')?;
            Stmt::Let(name, self.expr(0)?)
        } else {
            self.eat(b'[')?;
            let mut index = Vec::new();
            let tuple = self.peek()? == Lex::Punct(b'(');
            if tuple {
                self.next();
            }
            loop {
                let Lex::Number(n) = self.next()? else {
                    return None;
                };
                index.push(n);
                if !tuple || self.peek()? != Lex::Punct(b',') {
                    break;
                }
                self.next();
            }
            if tuple {
                self.eat(b')')?;
            }
            self.eat(b']')?;
            self.eat(b'=')?;
            Stmt::Store(first, index, self.expr(0)?)
        };
        self.eat(b';')?;
        (self.at == self.toks.len()).then_some(s)
    }

    /// Precedence climbing: `+ -` bind at 1, `* /` at 2, both left-associative; prefix `-`
    /// binds tighter than either.
    fn expr(&mut self, min: u8) -> Option<Expr<'a>> {
        let mut left = self.unary()?;
        while let Some(Lex::Punct(op @ (b'+' | b'-' | b'*' | b'/'))) = self.peek() {
            let prec = if matches!(op, b'+' | b'-') { 1 } else { 2 };
            if prec <= min {
                break;
            }
            self.next();
            let right = self.expr(prec)?;
            left = Expr::Binary(Box::new(left), op, Box::new(right));
        }
        Some(left)
    }

    fn unary(&mut self) -> Option<Expr<'a>> {
        match self.next()? {
            Lex::Punct(b'-') => Some(Expr::Neg(Box::new(self.unary()?))),
            Lex::Punct(b'(') => {
                let e = self.expr(0)?;
                self.eat(b')')?;
                Some(Expr::Paren(Box::new(e)))
            }
            Lex::Number(n) => Some(Expr::Word(n)),
            Lex::Ident(base) => {
                if self.peek() == Some(Lex::Punct(b'.')) {
                    self.next();
                    let Lex::Ident(member) = self.next()? else {
                        return None;
                    };
                    Some(Expr::Field(base, member))
                } else {
                    Some(Expr::Word(base))
                }
            }
            Lex::Punct(_) => None,
        }
    }
}

/// A token of the line-breaking algorithm.
#[derive(Clone, Copy)]
enum Tok<'a> {
    Text(&'a str),
    /// A place to break: `blank` spaces if not taken; if taken, a newline at the box's
    /// indentation plus `offset`, after writing `pre` (a trailing comma).
    Break {
        blank: isize,
        offset: isize,
        never: bool,
        pre: Option<char>,
    },
    /// A box: `consistent` boxes take all or none of their breaks.
    Begin {
        offset: isize,
        consistent: bool,
    },
    End,
}

#[derive(Default)]
struct Toks<'a>(Vec<Tok<'a>>);

impl<'a> Toks<'a> {
    fn text(&mut self, s: &'a str) {
        self.0.push(Tok::Text(s));
    }
    fn brk(&mut self, blank: isize) {
        self.0.push(Tok::Break {
            blank,
            offset: 0,
            never: false,
            pre: None,
        });
    }
    fn never_break(&mut self) {
        self.0.push(Tok::Break {
            blank: 0,
            offset: 0,
            never: true,
            pre: None,
        });
    }
    fn ibox(&mut self, offset: isize) {
        self.0.push(Tok::Begin {
            offset,
            consistent: false,
        });
    }
    fn cbox(&mut self, offset: isize) {
        self.0.push(Tok::Begin {
            offset,
            consistent: true,
        });
    }
    fn end(&mut self) {
        self.0.push(Tok::End);
    }

    /// The boxes and breaks prettyplease prints an expression with.
    fn expr(&mut self, e: &Expr<'a>) {
        match e {
            Expr::Word(w) => self.text(w),
            Expr::Field(base, member) => {
                self.cbox(INDENT);
                self.cbox(-INDENT);
                self.text(base);
                self.end();
                self.brk(0);
                self.text(".");
                self.text(member);
                self.end();
            }
            Expr::Neg(x) => {
                self.text("-");
                self.expr(x);
            }
            Expr::Paren(x) => {
                self.text("(");
                self.expr(x);
                self.text(")");
            }
            Expr::Binary(l, op, r) => {
                self.ibox(INDENT);
                self.ibox(-INDENT);
                self.expr(l);
                self.end();
                self.brk(1);
                self.text(match op {
                    b'+' => "+",
                    b'-' => "-",
                    b'*' => "*",
                    _ => "/",
                });
                self.text(" ");
                self.expr(r);
                self.end();
            }
        }
    }

    fn stmt(&mut self, s: &'a Stmt<'a>) {
        match s {
            Stmt::Let(name, e) => {
                self.ibox(0);
                self.text("let ");
                self.text(name);
                self.text(" = ");
                self.never_break();
                self.expr(e);
                self.end();
                self.text(";");
            }
            Stmt::Store(place, index, e) => {
                self.ibox(0);
                self.ibox(0);
                self.text(place);
                self.text("[");
                if let [i] = index.as_slice() {
                    self.text(i);
                } else {
                    self.text("(");
                    self.cbox(INDENT);
                    self.brk(0);
                    for (k, i) in index.iter().enumerate() {
                        self.text(i);
                        if k + 1 < index.len() {
                            self.text(",");
                            self.brk(1);
                        } else {
                            self.0.push(Tok::Break {
                                blank: 0,
                                offset: -INDENT,
                                never: false,
                                pre: Some(','),
                            });
                        }
                    }
                    self.end();
                    self.text(")");
                }
                self.text("]");
                self.text(" = ");
                self.never_break();
                self.expr(e);
                self.end();
                self.text(";");
                self.end();
            }
        }
    }
}

/// The sizes the algorithm decides with: for a break, the length of the text from it to the
/// next break that is not inside a box opened after it; for a box, the length from its start
/// to the first such break after its end. `toks` ends with a hard break at the outer level.
fn sizes(toks: &[Tok<'_>]) -> Vec<isize> {
    let mut size = vec![0isize; toks.len()];
    // Positions (text length before each token) and the pending tokens: breaks, box starts
    // and box ends not yet sized, as a stack (like the streaming algorithm's scan stack).
    let mut pos = 0isize;
    let mut stack: Vec<usize> = Vec::new();
    for (i, t) in toks.iter().enumerate() {
        match *t {
            Tok::Text(s) => pos += s.len() as isize,
            Tok::Begin { .. } => {
                size[i] = -pos;
                stack.push(i);
            }
            Tok::End => {
                size[i] = 1;
                stack.push(i);
            }
            Tok::Break { blank, .. } => {
                // Size what this break ends: closed boxes and the breaks inside them, then the
                // previous break of the same box.
                let mut depth = 0usize;
                while let Some(&j) = stack.last() {
                    match toks[j] {
                        Tok::Begin { .. } => {
                            if depth == 0 {
                                break;
                            }
                            stack.pop();
                            size[j] += pos;
                            depth -= 1;
                        }
                        Tok::End => {
                            stack.pop();
                            depth += 1;
                        }
                        Tok::Break { .. } => {
                            stack.pop();
                            size[j] += pos;
                            if depth == 0 {
                                break;
                            }
                        }
                        Tok::Text(_) => unreachable!("texts are not pending"),
                    }
                }
                size[i] = -pos;
                stack.push(i);
                pos += blank;
            }
        }
    }
    size
}

/// How a box is being printed.
#[derive(Clone, Copy)]
enum Frame {
    Fits,
    Broken { indent: isize, consistent: bool },
}

/// The statement `code` laid out as prettyplease lays it out at indentation `indent`, one
/// string per line with its indentation; `None` if `code` is not in the small language.
pub(super) fn layout(indent: usize, code: &str) -> Option<Vec<String>> {
    let parsed = Parser {
        toks: lex(code)?,
        at: 0,
    }
    .stmt()?;
    let mut toks = Toks::default();
    toks.stmt(&parsed);
    // The hard break after the statement, in the enclosing block.
    toks.brk(INFINITY);
    let toks = toks.0;
    let size = sizes(&toks);
    let indent = indent as isize;
    let mut lines = Vec::new();
    let mut line = " ".repeat(indent as usize);
    let mut pending = 0isize;
    let mut space = (MARGIN - indent).max(MIN_SPACE);
    // The enclosing block is broken and consistent (statements are on lines of their own).
    let mut frames = vec![Frame::Broken {
        indent,
        consistent: true,
    }];
    let mut current = indent;
    let last = toks.len() - 1;
    for (i, t) in toks[..last].iter().enumerate() {
        match *t {
            Tok::Text(s) => {
                line.extend(std::iter::repeat_n(' ', pending as usize));
                pending = 0;
                line.push_str(s);
                space -= s.len() as isize;
            }
            Tok::Begin { offset, consistent } => {
                if size[i] > space {
                    frames.push(Frame::Broken {
                        indent: current,
                        consistent,
                    });
                    current += offset;
                } else {
                    frames.push(Frame::Fits);
                }
            }
            Tok::End => {
                if let Some(Frame::Broken { indent, .. }) = frames.pop() {
                    current = indent;
                }
            }
            Tok::Break {
                blank,
                offset,
                never,
                pre,
            } => {
                let fits = never
                    || match frames.last() {
                        Some(Frame::Fits) | None => true,
                        Some(Frame::Broken { consistent, .. }) => !consistent && size[i] <= space,
                    };
                if fits {
                    pending += blank;
                    space -= blank;
                } else {
                    if let Some(c) = pre {
                        line.extend(std::iter::repeat_n(' ', pending as usize));
                        line.push(c);
                    }
                    lines.push(std::mem::take(&mut line));
                    let at = current + offset;
                    pending = at;
                    space = (MARGIN - at).max(MIN_SPACE);
                }
            }
        }
    }
    lines.push(line);
    Some(lines)
}
