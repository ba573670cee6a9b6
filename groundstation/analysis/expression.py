"""Expressions of channels, as PlotJuggler's custom series: ``ahf2_roll_deg - onboard_roll_deg``.

The text is parsed with Python's ``ast`` and only a whitelist is evaluated, on numpy arrays: numbers,
the names the caller allows (a bare name, or ``table.column``), ``+ - * / ** %``, unary minus, and the
functions of ``FUNCTIONS`` (numpy's); never ``eval`` of the text. Anything else is an
``ExpressionError`` whose message says what, for the dialog that asked. ``at_or_before`` is the rule
that puts another table's column on these rows' times: its newest row at or before each time.
"""

from __future__ import annotations

import ast
import operator

import numpy as np

from groundstation.errors import UserError

FUNCTIONS = {name: getattr(np, name) for name in (
    "abs", "sqrt", "sin", "cos", "tan", "arcsin", "arccos", "arctan", "arctan2", "degrees", "radians", "exp", "log",
    "log10", "hypot", "minimum", "maximum", "sign", "floor", "ceil")}
CONSTANTS = {"pi": np.pi, "e": np.e}
OPERATORS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
             ast.Pow: operator.pow, ast.Mod: operator.mod}
UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}


class ExpressionError(UserError):
    """An expression that cannot be evaluated: the message says why, for the user."""


def dotted(node: ast.AST) -> str | None:
    """``a`` or ``a.b`` as written; None for anything else."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return f"{node.value.id}.{node.attr}"
    return None


class Expression:
    """``text`` over ``known`` names (ExpressionError when it is not an allowed expression of them);
    ``names``: those it uses, in order of appearance."""

    def __init__(self, text: str, known):
        self.text = text.strip()
        if not self.text:
            raise ExpressionError("the expression is empty")
        try:
            self._tree = ast.parse(self.text, mode="eval").body
        except SyntaxError as error:
            raise ExpressionError(f"not an expression: {error.msg} at column {error.offset}") from None
        self.names: list[str] = []
        self._check(self._tree, known)

    def _check(self, node: ast.AST, known) -> None:
        name = dotted(node)
        if name is not None:
            if name in CONSTANTS or name in known:
                if name not in CONSTANTS and name not in self.names:
                    self.names.append(name)
                return
            raise ExpressionError(f"unknown channel {name!r}" + (f" (functions are called: {name}(x))" if name in FUNCTIONS else ""))
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return
        if isinstance(node, ast.BinOp) and type(node.op) in OPERATORS:
            self._check(node.left, known)
            self._check(node.right, known)
            return
        if isinstance(node, ast.UnaryOp) and type(node.op) in UNARY:
            self._check(node.operand, known)
            return
        if isinstance(node, ast.Call):
            if not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS):
                raise ExpressionError(f"unknown function {ast.unparse(node.func)!r} (allowed: {', '.join(FUNCTIONS)})")
            if node.keywords or not node.args:
                raise ExpressionError(f"{node.func.id}() takes values in order, without names")
            for arg in node.args:
                self._check(arg, known)
            return
        raise ExpressionError(f"{ast.unparse(node)!r} is not allowed: numbers, channels, + - * / ** %, and "
                              f"{', '.join(FUNCTIONS)} only")

    def evaluate(self, values: dict[str, np.ndarray]) -> np.ndarray:
        """The expression on ``values`` (an array per name of ``names``, all of one length), as float64."""
        with np.errstate(all="ignore"):  # NaN and inf where the maths has none (log of a negative): drawn as gaps
            return np.asarray(self._evaluate(self._tree, values), dtype=float)

    def _evaluate(self, node: ast.AST, values):
        name = dotted(node)
        if name is not None:
            return CONSTANTS[name] if name in CONSTANTS else values[name]
        if isinstance(node, ast.Constant):
            return node.value
        if isinstance(node, ast.BinOp):
            return OPERATORS[type(node.op)](self._evaluate(node.left, values), self._evaluate(node.right, values))
        if isinstance(node, ast.UnaryOp):
            return UNARY[type(node.op)](self._evaluate(node.operand, values))
        try:
            return FUNCTIONS[node.func.id](*(self._evaluate(a, values) for a in node.args))
        except TypeError as error:  # the wrong number of values for the function
            raise ExpressionError(f"{node.func.id}(): {error}") from None


def at_or_before(times_s: np.ndarray, their_times_s: np.ndarray, their_values: np.ndarray) -> np.ndarray:
    """``their_values`` at ``times_s``: each time takes their newest row at or before it (NaN before their first)."""
    index = np.searchsorted(their_times_s, times_s, side="right") - 1
    out = np.asarray(their_values, dtype=float)[np.maximum(index, 0)] if len(their_times_s) else np.full(len(times_s), np.nan)
    return np.where(index >= 0, out, np.nan)
