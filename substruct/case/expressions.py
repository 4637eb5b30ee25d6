r"""Safe expressions of ``x``, ``L`` and named case parameters, e.g. ``6/5*EA0*(1 - (x/L)**2/2)``.

A case file gives distributions along a rod, such as :math:`EA(x)` and :math:`m(x)` of eq (50),

.. math::  EA(x) = \tfrac65 EA_0 \bigl[1 - \tfrac12 (x/L)^2\bigr],

as a number, an expression string or polynomial coefficients ``{poly: [c0, c1, ...]}``
(:math:`c_0 + c_1 x + c_2 x^2 + \dots`).  Expression strings are parsed by :func:`ast.parse` and
the tree is walked here, node by node, against a whitelist:

* numbers (``int`` and ``float`` literals; no strings, booleans or complex numbers);
* names: ``x``, ``L``, the case parameters, the constant ``pi``;
* the operators ``+ - * / **`` and unary ``-``/``+``;
* calls of ``sin cos tan exp log sqrt abs`` with one positional argument.

Anything else (attribute access, subscripts, lambdas, comprehensions, keyword arguments, unknown
names, ``__import__``) raises :class:`ExpressionError` naming the offending piece.  Nothing is
ever passed to ``eval`` or ``exec``; evaluation is numpy arithmetic on float64 arrays, so an
overflow gives ``inf`` (caught by the callers' checks), never a huge Python integer.

Numbers go through the one numeric validation of :mod:`substruct.case.numbers`: an integer
of more than 30 digits is refused from the text, before it is parsed; a constant must be finite
and 0 or within ``1e-30 .. 1e30`` in magnitude; so must the value of :func:`scalar`.
"""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from typing import Any, Callable, Iterable, Mapping

import numpy as np

from substruct.case.numbers import digits_problem, number_problem

__all__ = ["ExpressionError", "Expression", "FUNCTIONS", "CONSTANTS", "compile_expression",
           "profile", "scalar"]

#: Functions an expression may call (one argument each).
FUNCTIONS: dict[str, Callable[[np.ndarray], np.ndarray]] = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log,
    "sqrt": np.sqrt, "abs": np.abs,
}
#: Named constants.
CONSTANTS: dict[str, float] = {"pi": float(np.pi)}
#: A number followed by a word, ``200 mm`` or ``6e6 N/mm^2``: a unit, which numbers do not take.
_UNIT = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z_%\u00b0\u00b5]"
                   r"[\w/^.*%\u00b0\u00b5-]*)\s*$")

_BINOPS: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: np.add, ast.Sub: np.subtract, ast.Mult: np.multiply, ast.Div: np.true_divide,
    ast.Pow: np.power,
}
_UNARY: dict[type, Callable[[Any], Any]] = {ast.USub: np.negative, ast.UAdd: np.positive}
_SYMBOLS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**",
            ast.FloorDiv: "//", ast.Mod: "%", ast.MatMult: "@", ast.BitXor: "^",
            ast.BitAnd: "&", ast.BitOr: "|", ast.LShift: "<<", ast.RShift: ">>",
            ast.Invert: "~", ast.Not: "not"}
#: Longest expression text accepted.
MAX_LENGTH = 2000
#: Deepest expression tree accepted.
MAX_DEPTH = 60


class ExpressionError(ValueError):
    """An expression that is not allowed or cannot be evaluated."""


@dataclass(frozen=True)
class Expression:
    """A checked expression: call it with the values of its names.

    Attributes:
        text: the source text.
        names: the free names it uses (``x``, ``L``, parameters), sorted.
    """

    text: str
    tree: ast.Expression
    names: tuple[str, ...]

    def __call__(self, **values: Any) -> np.ndarray:
        """Evaluate with numpy; ``values`` maps every name in :attr:`names` to a number or array."""
        missing = [n for n in self.names if n not in values]
        if missing:
            raise ExpressionError(f"no value for {', '.join(missing)} in {self.text!r}")
        env = {k: np.asarray(v, dtype=float) for k, v in values.items()}
        with np.errstate(all="ignore"):
            return np.asarray(_evaluate(self.tree.body, env), dtype=float)


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else text[:limit - 3] + "..."


def _piece(node: ast.AST, text: str) -> str:
    segment = ast.get_source_segment(text, node)
    return _short(segment if segment is not None else type(node).__name__)


def _at(node: ast.AST, text: str) -> str:
    """``'piece'`` or ``'piece' in 'text'`` when the piece is not the whole text."""
    piece = _piece(node, text)
    return repr(piece) if piece == text else f"{piece!r} in {_short(text)!r}"


def _check(node: ast.AST, text: str, allowed: frozenset[str], used: set[str],
           depth: int = 0) -> None:
    """Raise :class:`ExpressionError` unless every node of the tree is whitelisted."""
    if depth > MAX_DEPTH:
        raise ExpressionError(f"expression nested too deeply: {text[:60]!r}")
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise ExpressionError(f"only numbers are allowed as constants, not "
                                  f"{_at(node, text)}")
        problem = number_problem(node.value)
        if problem is not None:
            raise ExpressionError(f"number {_at(node, text)}: {problem}")
        return
    if isinstance(node, ast.Name):
        if node.id in FUNCTIONS:
            raise ExpressionError(f"function {node.id!r} must be called, as in {node.id}(x), "
                                  f"in {_short(text)!r}")
        if node.id not in allowed and node.id not in CONSTANTS:
            known = ", ".join(sorted(allowed | set(CONSTANTS)))
            raise ExpressionError(f"unknown name {node.id!r} in {_short(text)!r} "
                                  f"(known: {known})")
        if node.id not in CONSTANTS:
            used.add(node.id)
        return
    if isinstance(node, ast.BinOp):
        if type(node.op) not in _BINOPS:
            op = _SYMBOLS.get(type(node.op), type(node.op).__name__)
            raise ExpressionError(f"operator {op!r} is not allowed (only + - * / **) in "
                                  f"{_at(node, text)}")
        _check(node.left, text, allowed, used, depth + 1)
        _check(node.right, text, allowed, used, depth + 1)
        return
    if isinstance(node, ast.UnaryOp):
        if type(node.op) not in _UNARY:
            op = _SYMBOLS.get(type(node.op), type(node.op).__name__)
            raise ExpressionError(f"operator {op!r} is not allowed in {_at(node, text)}")
        _check(node.operand, text, allowed, used, depth + 1)
        return
    if isinstance(node, ast.Call):
        func = node.func
        if isinstance(func, ast.Constant):  # 0.3 (steel), 2 (x + 1)
            raise ExpressionError(
                f"{_piece(func, text)!r} followed by parentheses in {_at(node, text)}: a "
                f"comment goes after # outside the quotes ({_piece(func, text)} # ...), a "
                f"product needs * (2*(x + 1))")
        if not isinstance(func, ast.Name) or func.id not in FUNCTIONS:
            raise ExpressionError(
                f"call of {_piece(func, text)!r} is not allowed (functions: "
                f"{' '.join(FUNCTIONS)}) in {_at(node, text)}")
        if node.keywords or len(node.args) != 1 or isinstance(node.args[0], ast.Starred):
            raise ExpressionError(f"{func.id}() takes exactly one positional argument, in "
                                  f"{_at(node, text)}")
        _check(node.args[0], text, allowed, used, depth + 1)
        return
    what = {
        ast.Attribute: "attribute access", ast.Subscript: "subscript", ast.Lambda: "lambda",
        ast.ListComp: "comprehension", ast.SetComp: "comprehension",
        ast.DictComp: "comprehension", ast.GeneratorExp: "comprehension",
        ast.Compare: "comparison", ast.BoolOp: "boolean operator", ast.IfExp: "conditional",
        ast.NamedExpr: "assignment", ast.JoinedStr: "string", ast.List: "list",
        ast.Tuple: "tuple", ast.Dict: "dict", ast.Set: "set", ast.Starred: "starred argument",
    }.get(type(node), type(node).__name__)
    raise ExpressionError(f"{what} is not allowed: {_at(node, text)}")


def _evaluate(node: ast.AST, env: Mapping[str, np.ndarray]) -> np.ndarray:
    if isinstance(node, ast.Constant):
        if not isinstance(node.value, (int, float)):  # _check lets only numbers through
            raise ExpressionError(f"not a number: {node.value!r}")
        return np.asarray(node.value, dtype=np.float64)
    if isinstance(node, ast.Name):
        return env[node.id] if node.id in env else np.asarray(CONSTANTS[node.id], np.float64)
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_evaluate(node.left, env), _evaluate(node.right, env))
    if isinstance(node, ast.UnaryOp):
        return _UNARY[type(node.op)](_evaluate(node.operand, env))
    if isinstance(node, ast.Call):
        return FUNCTIONS[node.func.id](_evaluate(node.args[0], env))  # type: ignore[attr-defined]
    raise ExpressionError(f"cannot evaluate {type(node).__name__}")  # unreachable after _check


def compile_expression(text: str, names: Iterable[str] = ("x", "L")) -> Expression:
    """Parse and check ``text``; ``names`` are the names it may use (besides ``pi``).

    Raises:
        ExpressionError: syntax error, or anything outside the whitelist (the message names it).
    """
    if not isinstance(text, str):
        raise ExpressionError(f"an expression must be a string, got {text!r}")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"expression longer than {MAX_LENGTH} characters")
    if not text.strip():
        raise ExpressionError("empty expression")
    problem = digits_problem(text)
    if problem is not None:
        raise ExpressionError(f"{problem} in {_short(text.strip())!r}")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        unit = _UNIT.match(text)
        if unit and unit.group(2) not in (*names, *CONSTANTS, *FUNCTIONS):
            raise ExpressionError(
                f"units are not accepted in numbers: write {unit.group(1)!r} alone (the "
                f"numbers are in the case's consistent units, its units: note converts "
                f"nothing)") from None
        raise ExpressionError(f"syntax error in {_short(text)!r}: {err.msg}") from None
    except (RecursionError, MemoryError, ValueError):
        raise ExpressionError(f"cannot parse {text[:60]!r}") from None
    used: set[str] = set()
    clean = text.strip()
    _check(tree.body, clean, frozenset(names), used)
    return Expression(text=clean, tree=tree, names=tuple(sorted(used)))


def _number(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def profile(spec: Any, L: float, parameters: Mapping[str, float] | None = None
            ) -> Callable[[np.ndarray], np.ndarray]:
    r"""A vectorized callable ``f(x)`` from a number, an expression or ``{poly: [c0, c1, ...]}``.

    .. math::  f(x) = \sum_k c_k x^k \quad \text{for } \{poly: [c_0, c_1, \dots]\}

    Polynomial coefficients may themselves be numbers or expressions of ``L`` and the parameters
    (not of ``x``).  The result of ``f(x)`` has the shape of ``x``.

    Raises:
        ExpressionError: anything that is not one of the three forms, or a bad expression.
            The message does not repeat ``spec``: the case validation appends the value
            (``..., got {"poly": []}``) once.
    """
    params = dict(parameters or {})
    env = {**params, "L": float(L)}
    if _number(spec):
        problem = number_problem(spec)
        if problem is not None:
            raise ExpressionError(problem)
        value = float(spec)
        return lambda x: np.full(np.shape(x), value)
    if isinstance(spec, str):
        expr = compile_expression(spec, ["x", *env])

        def f(x: np.ndarray) -> np.ndarray:
            x = np.asarray(x, dtype=float)
            return np.broadcast_to(expr(x=x, **env), x.shape).astype(float)
        return f
    if isinstance(spec, Mapping):
        if set(spec) != {"poly"}:
            extra = sorted(map(str, set(spec) - {"poly"}))
            raise ExpressionError("a polynomial is written {poly: [c0, c1, ...]}"
                                  + (f" (unknown keys: {', '.join(extra)})" if extra else ""))
        coeffs = spec["poly"]
        if not isinstance(coeffs, (list, tuple)) or not coeffs:
            raise ExpressionError("poly needs a non-empty list of coefficients")
        c = np.array([scalar(v, env) for v in coeffs], dtype=float)

        def poly(x: np.ndarray) -> np.ndarray:
            with np.errstate(all="ignore"):  # an overflow is inf, refused by the callers
                return np.polynomial.polynomial.polyval(np.asarray(x, dtype=float), c)
        return poly
    raise ExpressionError("expected a number, an expression string or {poly: [c0, c1, ...]}")


def scalar(spec: Any, values: Mapping[str, float]) -> float:
    """A number, or an expression of the names in ``values`` (no ``x``) evaluated to a float.

    Raises:
        ExpressionError: a bad expression, or a number or value out of the range of
            :mod:`substruct.case.numbers` (not finite, or beyond ``1e-30 .. 1e30``).
    """
    if _number(spec):
        problem = number_problem(spec)
        if problem is not None:
            raise ExpressionError(problem)
        return float(spec)
    if isinstance(spec, str):
        expr = compile_expression(spec, list(values))
        value = float(expr(**{n: values[n] for n in expr.names}))
        problem = number_problem(value)
        if problem is not None:
            raise ExpressionError(f"{_short(expr.text)!r} = {value:.6g}: {problem}")
        return value
    raise ExpressionError(f"expected a number or an expression, got {spec!r}")
