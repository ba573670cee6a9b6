"""Expressions of channels, as PlotJuggler's custom series: ``ahf2_roll_deg - onboard_roll_deg``.

The text is parsed with Python's ``ast`` and only a whitelist is evaluated, on numpy arrays: numbers,
the names the caller allows (a bare name, or ``table.column``, each also of another session of the window
as its Channels tab lists them: ``S2:imu.gyr_x_rad_s``, ``S2:ahf2_roll_deg``), ``+ - * / ** %``, unary
minus, and the functions of ``FUNCTIONS`` (numpy's, each with its number of values); never ``eval`` of
the text. Anything else is an ``ExpressionError`` whose message says what, for the dialog that asked.

Python reads ``S2:imu`` as no expression, and no allowed expression has a colon of its own (no slices,
dictionaries or lambdas), so a colon between two names (``SESSION_COLON``, nothing around it) is read as a
dot by the parser, and every name is taken from the text as written (``written_name``): ``S2:imu.x`` and a
table ``S2``'s ``imu.x``, were there one, stay two names.

Whatever is typed, evaluating is bounded: every number becomes a float64 when parsed, so no Python
integer arithmetic ever runs (``10**10**10`` would hold the interpreter, and every other thread, for
ever); the parts made of numbers only are computed once when parsed, and one that is not a finite
float64 (``1/0``, ``10**400``, ``0**-1``, ``log(0)``) is refused there with its value; on channels,
overflow and division by zero give inf or NaN (drawn as gaps), never an exception; the text's length
and its number of parts are capped, and ``evaluate`` stops with an ``ExpressionError`` once past its
time budget. ``at_or_before`` is the rule that puts another table's column on these rows' times: its
newest row at or before each time.
"""

from __future__ import annotations

import ast
import operator
import re
import time

import numpy as np

from groundstation.errors import UserError

# name -> (numpy's function, how many values it takes); numpy's own extra arguments (out=, where=) never reachable
FUNCTIONS = {name: (getattr(np, name), 2 if name in ("arctan2", "hypot", "minimum", "maximum") else 1) for name in (
    "abs", "sqrt", "sin", "cos", "tan", "arcsin", "arccos", "arctan", "arctan2", "degrees", "radians", "exp", "log",
    "log10", "hypot", "minimum", "maximum", "sign", "floor", "ceil")}
CONSTANTS = {"pi": np.float64(np.pi), "e": np.float64(np.e)}
OPERATORS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
             ast.Pow: operator.pow, ast.Mod: operator.mod}
UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
MAX_CHARACTERS = 1000  # longer than any formula one types; bounds the parser's work
MAX_PARTS = 200  # numbers, names and operations: bounds the work per row, and the nesting within Python's recursion limit
SESSION_COLON = re.compile(r"(?<=\w):(?=[A-Za-z_])")  # "S2:imu": another session's name, then its channel's


class ExpressionError(UserError):
    """An expression that cannot be evaluated: the message says why, for the user."""


def written_name(node: ast.AST, text: str) -> str | None:
    """A name as ``text`` writes it (``a``, ``a.b``, ``S2:a.b``; spaces left out), when ``node`` is one
    parsed from ``text`` with its session colons read as dots; None for anything else."""
    base = node
    while isinstance(base, ast.Attribute):
        base = base.value
    if not isinstance(base, ast.Name):
        return None
    return "".join(ast.get_source_segment(text, node).split())


def as_float64(value: int | float) -> np.float64:
    """A number as written, in float64: an integer beyond its range is inf, as 1e400 is."""
    try:
        return np.float64(value)
    except OverflowError:
        return np.float64(np.inf)


class Expression:
    """``text`` over ``known`` names (ExpressionError when it is not an allowed expression of them, or
    a part of numbers only is not a finite float64); ``names``: those it uses, in order of appearance."""

    def __init__(self, text: str, known):
        self.text = text.strip()
        if not self.text:
            raise ExpressionError("the expression is empty")
        if len(self.text) > MAX_CHARACTERS:
            raise ExpressionError(f"the expression is {len(self.text)} characters long: {MAX_CHARACTERS} at most")
        try:
            tree = ast.parse(SESSION_COLON.sub(".", self.text), mode="eval").body  # as long as the text: its places hold
        except SyntaxError as error:
            raise ExpressionError(f"not an expression: {error.msg} at column {error.offset}") from None
        except (ValueError, RecursionError, MemoryError):  # a NUL character; nesting the parser will not take
            raise ExpressionError("not an expression Python can read") from None
        parts = sum(isinstance(node, ast.expr) for node in ast.walk(tree))
        if parts > MAX_PARTS:
            raise ExpressionError(f"the expression has {parts} parts (numbers, names, operations): {MAX_PARTS} at most")
        self.names: list[str] = []
        with np.errstate(all="ignore"):
            self._tree = self._compile(tree, known)

    def _compile(self, node: ast.AST, known):
        """The checked tree: ("name", name), ("value", float64), or (function, operand nodes ...); the
        parts of numbers only computed now."""
        name = written_name(node, self.text)
        if name is not None:
            if name in CONSTANTS:
                return ("value", CONSTANTS[name])
            if name in known:
                if name not in self.names:
                    self.names.append(name)
                return ("name", name)
            session = name.split(":")[0] if ":" in name else None
            if session is not None and not any(k.startswith(f"{session}:") for k in known):
                raise ExpressionError(f"unknown channel {name!r}: there is no session {session} in this window")
            raise ExpressionError(f"unknown channel {name!r}" + (f" (functions are called: {name}(x))" if name in FUNCTIONS else ""))
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return self._number(node, as_float64(node.value))
        if isinstance(node, ast.BinOp) and type(node.op) in OPERATORS:
            return self._apply(node, OPERATORS[type(node.op)], [node.left, node.right], known)
        if isinstance(node, ast.UnaryOp) and type(node.op) in UNARY:
            return self._apply(node, UNARY[type(node.op)], [node.operand], known)
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS):
                raise ExpressionError(f"unknown function {ast.unparse(node.func)!r} (allowed: {', '.join(FUNCTIONS)})")
            function, count = FUNCTIONS[node.func.id]
            if node.keywords or any(isinstance(a, ast.Starred) for a in node.args):
                raise ExpressionError(f"{node.func.id}() takes values in order, without names")
            if len(node.args) != count:
                raise ExpressionError(f"{node.func.id}() takes {count} value{'s' if count > 1 else ''}, "
                                      f"not {len(node.args)}: {ast.unparse(node)}")
            return self._apply(node, function, node.args, known)
        raise ExpressionError(f"{ast.unparse(node)!r} is not allowed: numbers, channels, + - * / ** %, and "
                              f"{', '.join(FUNCTIONS)} only")

    def _apply(self, node: ast.AST, function, operands: list[ast.AST], known):
        compiled = [self._compile(operand, known) for operand in operands]
        if all(c[0] == "value" for c in compiled):  # numbers only: computed once, here
            return self._number(node, np.float64(function(*(c[1] for c in compiled))))
        return (function, *compiled)

    @staticmethod
    def _number(node: ast.AST, value: np.float64):
        if not np.isfinite(value):
            raise ExpressionError(f"{ast.unparse(node)} is {value} in float64 (overflow, division by zero or "
                                  f"outside the function's domain)")
        return ("value", value)

    def evaluate(self, values: dict[str, np.ndarray], budget_s: float | None = None) -> np.ndarray:
        """The expression on ``values`` (an array per name of ``names``, all of one length), as float64;
        an ExpressionError once it has taken longer than ``budget_s``."""
        floats = {name: np.asarray(v, dtype=np.float64) for name, v in values.items()}
        deadline = None if budget_s is None else time.perf_counter() + budget_s
        with np.errstate(all="ignore"):  # NaN and inf where the maths has none (log of a negative): drawn as gaps
            try:
                return np.asarray(self._evaluate(self._tree, floats, deadline), dtype=np.float64)
            except TimeoutError:
                raise ExpressionError(f"took longer than {budget_s:g} s to compute") from None

    def _evaluate(self, node, values, deadline):
        if node[0] == "value":
            return node[1]
        if node[0] == "name":
            return values[node[1]]
        result = node[0](*(self._evaluate(operand, values, deadline) for operand in node[1:]))
        if deadline is not None and time.perf_counter() > deadline:
            raise TimeoutError
        return result


def at_or_before(times_s: np.ndarray, their_times_s: np.ndarray, their_values: np.ndarray) -> np.ndarray:
    """``their_values`` at ``times_s``: each time takes their newest row at or before it (NaN before their first)."""
    index = np.searchsorted(their_times_s, times_s, side="right") - 1
    out = np.asarray(their_values, dtype=float)[np.maximum(index, 0)] if len(their_times_s) else np.full(len(times_s), np.nan)
    return np.where(index >= 0, out, np.nan)
