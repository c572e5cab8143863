"""Numbers written as text in a case file or on the command line: ``"pi/8"``, ``"2*pi/1.6"``.

Only numbers, ``pi``, ``+ - * / **`` and parentheses are allowed, read by walking Python's syntax
tree: no name but ``pi`` is looked up and nothing is called, so an expression in a shared case
file never runs code.
"""

from __future__ import annotations

import ast
import math
import operator
from collections.abc import Callable
from typing import Any

from oscillator.errors import InputError
from oscillator.text import printable

__all__ = ["MAX_EXPRESSION", "parse_value"]

#: The longest expression evaluated, in characters (``"2*pi/3"`` is 6).
MAX_EXPRESSION = 200

_OPERATORS: dict[type, Callable[..., float]] = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
    ast.USub: operator.neg,
    ast.UAdd: operator.pos,
}


def parse_value(value: Any, *, field: str) -> Any:
    """A number from a case file: a TOML number, or a string such as ``"pi/8"``.

    Only numbers, ``pi``, ``+ - * / **`` and parentheses are allowed in strings, at most
    :data:`MAX_EXPRESSION` characters.
    """
    if not isinstance(value, str):
        return value
    if len(value) > MAX_EXPRESSION:
        raise InputError(
            f"{field} is an expression of {len(value):,} characters; at most {MAX_EXPRESSION} are read. "
            f'Write a number or a short expression such as "pi/8"',
            field=field,
        )

    def evaluate(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return evaluate(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.BinOp) and type(node.op) in _OPERATORS:
            return _OPERATORS[type(node.op)](evaluate(node.left), evaluate(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPERATORS:
            return _OPERATORS[type(node.op)](evaluate(node.operand))
        raise ValueError(node)

    try:
        result = evaluate(ast.parse(value.strip(), mode="eval"))
    except (SyntaxError, ValueError, TypeError, ArithmeticError, RecursionError, MemoryError) as exc:
        raise InputError(
            f"{field} = {printable(repr(value))} is not a number; write a number or an expression of numbers "
            f'and pi such as "pi/8"',
            field=field,
        ) from exc
    return result
