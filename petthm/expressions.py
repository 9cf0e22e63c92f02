"""Expressions of position in option values (``../shared/docs/reservoir.md``
section 2; manual: user guide, options reference): numbers, the coordinates
``x``, ``y`` (and ``z`` in 3D; metres, the last one points up), ``+ - * /
**``, parentheses, comparisons, ``where(c,a,b)``, ``exp log sqrt sin cos
abs`` and the element-wise ``min(a,b)``, ``max(a,b)``.

The text is parsed into Python's syntax tree (``ast.parse``), every node is
checked against an allowlist, and the tree is evaluated with numpy over an
array of points; nothing is handed to ``eval``.  A value that is not in the
allowlist (an unknown name, an attribute, a string, a keyword argument) is
an ``InputError`` naming the option, the offending piece and what is
accepted, and so is a result that is not finite.
"""
from __future__ import annotations

import ast
import operator
from collections.abc import Callable

import numpy as np

from petthm.errors import InputError

COORDINATES = ("x", "y", "z")

#: the functions and their numbers of arguments
FUNCTIONS: dict[str, tuple[Callable, int]] = {
    "exp": (np.exp, 1), "log": (np.log, 1), "sqrt": (np.sqrt, 1), "sin": (np.sin, 1),
    "cos": (np.cos, 1), "abs": (np.abs, 1), "min": (np.minimum, 2), "max": (np.maximum, 2),
    "where": (np.where, 3)}

_BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
           ast.Pow: operator.pow}
_UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
_COMPARE = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge,
            ast.Eq: operator.eq, ast.NotEq: operator.ne}

ACCEPTED = ("numbers, x y z, + - * / **, parentheses, comparisons (< <= > >= == !=), "
            + ", ".join(f"{name}({','.join('abc'[:n])})" for name, (_, n) in FUNCTIONS.items()))


class Expression:
    """One option value as a function of position: ``expr(points)`` (n, d)
    -> (n,) float (collective nowhere; the same on every rank)."""

    def __init__(self, text: str, option: str, dim: int = 3):
        self.text, self.option, self.dim = text, option, dim
        try:
            tree = ast.parse(text.strip(), mode="eval")
        except SyntaxError:
            raise InputError(f"option {option} = {text!r}: not an expression ({ACCEPTED})") from None
        self._tree = tree.body
        self.symbols: set[str] = set()
        self._check(self._tree)

    def __str__(self) -> str:
        return self.text

    def __repr__(self) -> str:
        return f"Expression({self.text!r})"

    def __eq__(self, other) -> bool:
        return isinstance(other, Expression) and other.text == self.text

    def __hash__(self) -> int:
        return hash(self.text)

    def in_dimension(self, dim: int) -> Expression:
        """The same text checked for a mesh of ``dim`` dimensions (in 2D there is no z)."""
        return self if dim == self.dim else Expression(self.text, self.option, dim)

    @property
    def constant(self) -> bool:
        """Whether the value does not depend on position."""
        return not self.symbols

    def value(self) -> float:
        """The value of a constant expression."""
        if not self.constant:
            raise InputError(f"option {self.option} = {self.text!r}: a number is needed here, "
                             f"not a function of {', '.join(sorted(self.symbols))}")
        return float(self(np.zeros((1, self.dim)))[0])

    def __call__(self, points) -> np.ndarray:
        points = np.asarray(points, dtype=float).reshape(-1, self.dim)
        coords = {name: points[:, k] for k, name in enumerate(COORDINATES[:self.dim])}
        with np.errstate(all="ignore"):
            out = np.broadcast_to(np.asarray(self._evaluate(self._tree, coords), dtype=float),
                                  (len(points),)).copy()
        bad = ~np.isfinite(out)
        if bad.any():
            where = ", ".join(f"{c:g}" for c in points[np.argmax(bad)])
            raise InputError(f"option {self.option} = {self.text!r} is not finite at ({where})")
        return out

    # -- the allowlist ---------------------------------------------------------------------
    def _refuse(self, what: str):
        raise InputError(f"option {self.option} = {self.text!r}: {what} is not accepted; "
                         f"accepted: {ACCEPTED}")

    def _check(self, node) -> None:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, bool) or not isinstance(node.value, (int, float)) or \
                    not np.isfinite(float(node.value) if abs(node.value) < 1e308 else np.inf):
                self._refuse(f"the constant {node.value!r}")
        elif isinstance(node, ast.Name):
            if node.id not in COORDINATES[:self.dim]:
                self._refuse(f"the name '{node.id}'" + (" (a function: write it with its arguments)"
                                                        if node.id in FUNCTIONS else ""))
            self.symbols.add(node.id)
        elif isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
            self._check(node.left)
            self._check(node.right)
        elif isinstance(node, ast.UnaryOp) and type(node.op) in _UNARY:
            self._check(node.operand)
        elif isinstance(node, ast.Compare) and all(type(op) in _COMPARE for op in node.ops):
            for n in (node.left, *node.comparators):
                self._check(n)
        elif isinstance(node, ast.Call):
            self._check_call(node)
        else:
            self._refuse(f"'{ast.unparse(node)}'")

    def _check_call(self, node: ast.Call) -> None:
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS or node.keywords:
            self._refuse(f"the call '{ast.unparse(node)}'")
        if len(node.args) != FUNCTIONS[name][1]:
            self._refuse(f"'{ast.unparse(node)}' with {len(node.args)} argument(s) "
                         f"({name} takes {FUNCTIONS[name][1]})")
        for arg in node.args:
            self._check(arg)

    def _evaluate(self, node, coords: dict):
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            return coords[node.id]
        if isinstance(node, ast.BinOp):
            left, right = self._evaluate(node.left, coords), self._evaluate(node.right, coords)
            return _BINARY[type(node.op)](left, right)
        if isinstance(node, ast.UnaryOp):
            return _UNARY[type(node.op)](self._evaluate(node.operand, coords))
        if isinstance(node, ast.Compare):
            left, result = self._evaluate(node.left, coords), True
            for op, right in zip(node.ops, node.comparators, strict=True):
                right = self._evaluate(right, coords)
                result = np.logical_and(result, _COMPARE[type(op)](left, right))
                left = right
            return result
        fn = FUNCTIONS[node.func.id][0]
        return fn(*(self._evaluate(a, coords) for a in node.args))


def split_list(text: str) -> list[str]:
    """A comma list of expressions split at its top-level commas only
    (``where(z<0,1,2),3``: two items)."""
    items, depth, start = [], 0, 0
    for k, ch in enumerate(text):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch == "," and depth == 0:
            items.append(text[start:k])
            start = k + 1
    items.append(text[start:])
    return [s.strip() for s in items]


def number_or_expression(option: str) -> Callable:
    """A parser of option ``-option``'s value (``params.param(parse=...)``):
    a float for a number, else an ``Expression`` of position (checked for
    3D; ``Expression.in_dimension`` re-checks it for a 2D mesh)."""
    def parse(text):
        if isinstance(text, (int, float, Expression)):
            return float(text) if not isinstance(text, Expression) else text
        try:
            return float(text)
        except ValueError:
            return Expression(str(text), "-" + option)
    return parse


def values_at(value, points) -> np.ndarray:
    """A number or an ``Expression`` at ``points`` (n, d): (n,) floats."""
    if isinstance(value, Expression):
        return value.in_dimension(np.shape(points)[-1])(points)
    return np.full(len(points), float(value))
