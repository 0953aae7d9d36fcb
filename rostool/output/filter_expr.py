"""Safe filter expressions over a message `m`, e.g. `m.data == "go" and m.header.seq % 2 == 0`.

The text is parsed with Python's own grammar but never executed: only a small whitelist of node kinds
(field access, indexing, literals, arithmetic, comparisons, and/or/not, a few functions and string
methods) is compiled into closures. Anything else is rejected with the offending piece named.
"""

from __future__ import annotations

import ast
import operator
from collections.abc import Callable, Collection
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from rostool.errors import RostoolError
from rostool.output.plain import is_message

Evaluator = Callable[[Any], Any]

_BINARY: dict[type[ast.operator], Callable[[Any, Any], Any]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv,
    ast.Mod: operator.mod,
}
_COMPARE: dict[type[ast.cmpop], Callable[[Any, Any], bool]] = {
    ast.Eq: operator.eq,
    ast.NotEq: operator.ne,
    ast.Lt: operator.lt,
    ast.LtE: operator.le,
    ast.Gt: operator.gt,
    ast.GtE: operator.ge,
    ast.In: lambda a, b: a in b,
    ast.NotIn: lambda a, b: a not in b,
}
_FUNCTIONS: dict[str, Callable[..., Any]] = {
    "len": len, "abs": abs, "round": round, "min": min, "max": max,
    "int": int, "float": float, "str": str, "bool": bool,
}  # fmt: skip
_STRING_METHODS = frozenset(
    {"startswith", "endswith", "lower", "upper", "strip", "find", "count", "split", "isdigit"}
)


class FilterError(RostoolError):
    pass


@dataclass(frozen=True)
class Bindings:
    """The message plus extra names a caller offers (e.g. `bag filter`'s `topic` and `t`)."""

    m: object
    extra: dict[str, object]


# Extra names the expression being compiled may use (set by compile_filter's `names`).
_EXTRA_NAMES: ContextVar[frozenset[str]] = ContextVar("_EXTRA_NAMES", default=frozenset())


def compile_filter(text: str, names: Collection[str] = ()) -> Callable[[object], bool]:
    """Compile `text` into a predicate over a message; raises FilterError for anything unsafe or invalid.

    With `names`, the expression may also use those names; call the predicate with `Bindings(msg, {...})`.
    """
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise FilterError(f"invalid filter expression {text!r}: {err.msg}") from err
    token = _EXTRA_NAMES.set(frozenset(names))
    try:
        evaluate = _compile(tree.body, text)
    finally:
        _EXTRA_NAMES.reset(token)

    def predicate(msg: object) -> bool:
        try:
            return bool(evaluate(msg))
        except (LookupError, TypeError, ValueError, ZeroDivisionError, AttributeError):
            return False

    return predicate


def _compile(node: ast.AST, text: str) -> Evaluator:
    if isinstance(node, ast.Constant):
        value = node.value
        return lambda _m: value
    if isinstance(node, ast.Name):
        if node.id == "m":
            return lambda m: m.m if isinstance(m, Bindings) else m
        if node.id in _EXTRA_NAMES.get():
            name = node.id
            return lambda m: m.extra[name]
        raise FilterError(f"unknown name {node.id!r} in filter {text!r}: the message is `m`")
    if isinstance(node, ast.Attribute):
        return _attribute(node, text)
    if isinstance(node, ast.Subscript):
        target, index = _compile(node.value, text), _compile(node.slice, text)
        return lambda m: target(m)[index(m)]
    if isinstance(node, (ast.List, ast.Tuple, ast.Set)):
        items = [_compile(item, text) for item in node.elts]
        return lambda m: tuple(item(m) for item in items)
    if isinstance(node, ast.BoolOp):
        parts = [_compile(value, text) for value in node.values]
        if isinstance(node.op, ast.And):
            return lambda m: all(part(m) for part in parts)
        return lambda m: any(part(m) for part in parts)
    if isinstance(node, ast.UnaryOp):
        operand = _compile(node.operand, text)
        if isinstance(node.op, ast.Not):
            return lambda m: not operand(m)
        if isinstance(node.op, ast.USub):
            return lambda m: -operand(m)
        if isinstance(node.op, ast.UAdd):
            return operand
    if isinstance(node, ast.BinOp) and type(node.op) in _BINARY:
        left, right, op = _compile(node.left, text), _compile(node.right, text), _BINARY[type(node.op)]
        return lambda m: op(left(m), right(m))
    if isinstance(node, ast.Compare):
        return _compare(node, text)
    if isinstance(node, ast.Call):
        return _call(node, text)
    piece = ast.get_source_segment(text, node) or type(node).__name__
    raise FilterError(f"filter {text!r}: {piece!r} is not allowed (use fields of m, literals, comparisons)")


def _attribute(node: ast.Attribute, text: str) -> Evaluator:
    name = node.attr
    if name.startswith("_"):
        raise FilterError(f"filter {text!r}: field {name!r} is not allowed")
    target = _compile(node.value, text)

    def get(m: Any) -> Any:
        value = target(m)
        if not is_message(value):
            raise AttributeError(name)
        return getattr(value, name)

    return get


def _compare(node: ast.Compare, text: str) -> Evaluator:
    left = _compile(node.left, text)
    steps = [
        (_COMPARE[type(op)], _compile(right, text))
        for op, right in zip(node.ops, node.comparators, strict=True)
    ]

    def compare(m: Any) -> bool:
        current = left(m)
        for op, right in steps:
            nxt = right(m)
            if not op(current, nxt):
                return False
            current = nxt
        return True

    return compare


def _call(node: ast.Call, text: str) -> Evaluator:
    if node.keywords:
        raise FilterError(f"filter {text!r}: keyword arguments are not allowed")
    args = [_compile(arg, text) for arg in node.args]
    func = node.func
    if isinstance(func, ast.Name) and func.id in _FUNCTIONS:
        function = _FUNCTIONS[func.id]
        return lambda m: function(*(arg(m) for arg in args))
    if isinstance(func, ast.Attribute) and func.attr in _STRING_METHODS:
        target, method = _compile(func.value, text), func.attr

        def call_method(m: Any) -> Any:
            value = target(m)
            if not isinstance(value, str):
                raise TypeError(method)
            return getattr(value, method)(*(arg(m) for arg in args))

        return call_method
    piece = ast.get_source_segment(text, func) or "call"
    raise FilterError(f"filter {text!r}: calling {piece!r} is not allowed")
