"""Mutant schemata: every mutant of a source file written into one copy of the file, each behind
a run-time switch, so that one build serves all of them (mutate.py `schemata`).

A mutant replaces text; the schema keeps both texts and picks one at run time:

  an expression   (active() == k ? T(mutated) : T(original)), when the changed text, widened to
                  the smallest complete expression around it (bounded by one of ( , = [ { ? :
                  return on the left and ) , ; ] } ? : on the right, brackets balanced, no
                  top-level comma, semicolon or assignment), has the same value type T both
                  ways (a static_assert on the decayed types, an Eigen expression taken as the
                  matrix it evaluates to: a mutant that changes a type cannot hide behind a
                  conversion);
  a statement     if (active() == k) { mutated } else { original }, when the change spans
                  whole statements inside a function.

A wrap the compiler refuses (a constant expression, a declaration, a type, a label) is taken
out again, found from the lines the compiler names, and that mutant is built on its own, as
before schemata (mutate.py's slots). AP_MUTANT in the environment selects the mutant (its
number in the run); unset, the schema behaves exactly as the original file: the unmutated
suites run on the schema build before any mutant and must pass.
"""
import re

HEADER = r"""// Mutant schema (test/mutants/schemata.py): AP_MUTANT=<n> switches mutant n on.
#include <cstdlib>
#include <type_traits>
namespace ap_mutant_schema {
inline int active() {
  static const int n = [] {
    const char* v = std::getenv("AP_MUTANT");
    return v ? std::atoi(v) : -1;
  }();
  return n;
}
// The value an expression stands for: its own type, or for an Eigen expression the matrix it
// evaluates to (two expression trees of one matrix type are then one type).
template <class T, class = void>
struct Plain {
  using type = std::decay_t<T>;
};
template <class T>
struct Plain<T, std::void_t<typename std::decay_t<T>::PlainObject>> {
  using type = typename std::decay_t<T>::PlainObject;
};
// A and B as decltype((expression)) gives them: one type, lvalues of it, stay one lvalue (as
// '?:' keeps them); otherwise the value both stand for.
template <class A, class B>
struct Same {
  static_assert(std::is_same<typename Plain<A>::type, typename Plain<B>::type>::value,
                "a schema's mutated expression has another type than the original");
  using type = std::conditional_t<std::is_same<A, B>::value, A, typename Plain<A>::type>;
};
}  // namespace ap_mutant_schema
"""

TOKEN = re.compile(r"""
    (?P<skip>//[^\n]*|/\*.*?\*/|^[ \t]*\#[^\n]*(?:\\\n[^\n]*)*|\s+)
  | (?P<string>R"(?P<delim>[^(\s]*)\(.*?\)(?P=delim)"|"(?:\\.|[^"\\\n])*"|'(?:\\.|[^'\\\n])*')
  | (?P<number>\.?\d(?:[\w.]|[eEpP][+-])*)
  | (?P<word>[A-Za-z_]\w*)
  | (?P<op>::|->\*?|\.\*|\+\+|--|<<=|>>=|<=>|<<|>>|<=|>=|==|!=|&&|\|\||[-+*/%&|^]=|\.\.\.|.)
""", re.S | re.M | re.X)

OPEN = {"(": ")", "[": "]", "{": "}"}
CLOSE = {v: k for k, v in OPEN.items()}
LEFT_BOUNDS = {"(", ",", "=", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "<<=", ">>=",
               "[", "{", "?", ":", "return", "throw"}
RIGHT_BOUNDS = {")", ",", ";", "]", "}", "?", ":"}
ASSIGNMENTS = {"=", "+=", "-=", "*=", "/=", "%=", "&=", "|=", "^=", "<<=", ">>="}


def tokens(text):
    """(start, end, text) of each token, comments, strings' insides and preprocessor lines
    skipped (a string literal is one token)."""
    out = []
    for m in TOKEN.finditer(text):
        if m.lastgroup != "skip":
            out.append((m.start(), m.end(), m.group()))
    return out


def covering(toks, start, end):
    """Indices (i, j) of the first and last token overlapping [start, end); an empty range
    takes the token after it."""
    i = next((n for n, t in enumerate(toks) if t[1] > start), len(toks) - 1)
    j = max((n for n, t in enumerate(toks) if t[0] < end), default=i)
    return i, max(i, j)


def balance(toks, i, j):
    """Widens [i, j] until its brackets pair up inside it; None if they cannot."""
    for _ in range(10000):
        stack, widened = [], False
        for n in range(i, j + 1):
            t = toks[n][2]
            if t in OPEN:
                stack.append(n)
            elif t in CLOSE:
                if stack:
                    stack.pop()
                else:  # closes a bracket opened before i: take its opener in
                    k, d = n - 1, 0
                    while k >= 0:
                        if toks[k][2] in CLOSE:
                            d += 1
                        elif toks[k][2] in OPEN:
                            if d == 0:
                                break
                            d -= 1
                        k -= 1
                    if k < 0:
                        return None
                    i, widened = min(i, k), True
                    break
        if widened:
            continue
        if stack:  # opens a bracket closed after j: take its closer in
            k, d = j + 1, 0
            while k < len(toks):
                if toks[k][2] in OPEN:
                    d += 1
                elif toks[k][2] in CLOSE:
                    if d == 0:
                        break
                    d -= 1
                k += 1
            if k >= len(toks):
                return None
            j = k
            continue
        return i, j
    return None


def top_level(toks, i, j):
    """The tokens of [i, j] outside any bracket."""
    depth = 0
    for n in range(i, j + 1):
        t = toks[n][2]
        if t in OPEN:
            depth += 1
        elif t in CLOSE:
            depth -= 1
        elif depth == 0:
            yield t


def expression_span(toks, i, j):
    """The smallest complete expression around tokens [i, j], or None."""
    for _ in range(400):
        span = balance(toks, i, j)
        if span is None:
            return None
        i, j = span
        inside = list(top_level(toks, i, j))
        if set(inside) & ({",", ";", "{", "}"} | ASSIGNMENTS):
            return None
        # A conditional whole: a ':' takes its '?' (to the left) in, a '?' its ':'.
        questions, colons = inside.count("?"), inside.count(":")
        if colons > questions and i > 0:
            i -= 1
            continue
        if questions > colons and j + 1 < len(toks):
            j += 1
            continue
        if i == 0 or j + 1 >= len(toks):
            return None
        left, right = toks[i - 1][2], toks[j + 1][2]
        if left in (";", "}"):
            return None
        if left not in LEFT_BOUNDS:
            i -= 1
            continue
        if right not in RIGHT_BOUNDS:
            j += 1
            continue
        return i, j
    return None


def statement_span(toks, i, j):
    """The whole statements around tokens [i, j] inside a block, or None."""
    span = balance(toks, i, j)
    if span is None:
        return None
    i, j = span
    # Back to just after a ';', '{' or '}' at this depth.
    depth = 0
    while i > 0:
        t = toks[i - 1][2]
        if t in CLOSE:
            depth += 1
        elif t in OPEN:
            if depth == 0:
                break
            depth -= 1
        elif t == ";" and depth == 0:
            break
        i -= 1
    if depth != 0 or i == 0 or toks[i - 1][2] in ("(", "["):
        return None
    # On to a ';' at this depth, or the '}' that ends a block opened inside.
    depth = 0
    n = i
    end = None
    while n < len(toks):
        t = toks[n][2]
        if t in OPEN:
            depth += 1
        elif t in CLOSE:
            depth -= 1
            if depth < 0:
                return None
            if depth == 0 and t == "}" and n >= j:
                nxt = toks[n + 1][2] if n + 1 < len(toks) else ""
                if nxt not in ("else", ";", ")", ","):
                    end = n
                    break
        elif t == ";" and depth == 0 and n >= j:
            end = n
            break
        n += 1
    if end is None or toks[i][2] in ("else", "case", "default", "public", "private",
                                     "protected", "template", "namespace"):
        return None
    return i, end


class Wrap:
    """One mutant's switch in a schema: the original text's span and its two versions."""

    def __init__(self, number, mutant_id, start, end, original, mutated, kind):
        self.number, self.mutant_id = number, mutant_id
        self.start, self.end = start, end
        self.original, self.mutated, self.kind = original, mutated, kind

    def text(self):
        # Written out, not a macro: the compiler then names the switch's own line.
        on = f"(::ap_mutant_schema::active() == {self.number})"
        if self.kind == "expression":
            # Both sides converted to the original's value type (checked equal to the mutated
            # one's), so that the two sides of '?:' agree and the unswitched value is unchanged.
            same = (f"::ap_mutant_schema::Same<decltype(({self.original})), "
                    f"decltype(({self.mutated}))>::type")
            return (f"({on} ? static_cast<{same}>({self.mutated}) "
                    f": static_cast<{same}>({self.original}))")
        # Each text on lines of its own: a line comment in one cannot swallow the braces.
        return f"if {on} {{\n{self.mutated}\n}} else {{\n{self.original}\n}}"


def plan(text, number, mutant_id, pairs):
    """The wraps of one mutant (one per original/mutant pair), or None when a pair has no span
    that a switch can hold."""
    toks = tokens(text)
    wraps = []
    for original, replacement in pairs:
        at = text.find(original)
        if at < 0 or text.count(original) != 1:
            return None
        prefix = 0
        while (prefix < min(len(original), len(replacement)) and
               original[prefix] == replacement[prefix]):
            prefix += 1
        suffix = 0
        while (suffix < min(len(original), len(replacement)) - prefix and
               original[-1 - suffix] == replacement[-1 - suffix]):
            suffix += 1
        start, end = at + prefix, at + len(original) - suffix
        i, j = covering(toks, start, max(end, start + 1))
        mutated_text = text[:at] + replacement + text[at + len(original):]
        delta = len(replacement) - len(original)
        chosen = None
        for kind, finder in (("expression", expression_span), ("statement", statement_span)):
            span = finder(toks, i, j)
            if span is not None:
                s, e = toks[span[0]][0], toks[span[1]][1]
                if s <= start and e >= end:  # the whole change inside the switch
                    chosen = (kind, s, e)
                    break
        if chosen is None:
            return None
        kind, s, e = chosen
        original_span = text[s:e]
        mutated_span = mutated_text[s:e + delta]
        if "#" in original_span or "#" in mutated_span:  # a preprocessor line inside
            return None
        wraps.append(Wrap(number, mutant_id, s, e, original_span, mutated_span, kind))
    return wraps


def build(text, wraps):
    """The schema: the file with every wrap in place (none may overlap) and the switch's header
    first; also each wrap's first and last line in the schema."""
    wraps = sorted(wraps, key=lambda w: w.start)
    pieces, lines, last = [HEADER], {}, 0
    line = HEADER.count("\n") + 1
    for w in wraps:
        before = text[last:w.start]
        pieces.append(before)
        line += before.count("\n")
        body = w.text()
        lines.setdefault(w.mutant_id, []).append((line, line + body.count("\n")))
        pieces.append(body)
        line += body.count("\n")
        last = w.end
    pieces.append(text[last:])
    return "".join(pieces), lines


def overlapping(wraps, candidate):
    return any(not (c.end <= w.start or c.start >= w.end) for w in wraps for c in candidate)
