"""The expression language: parse against an allow-list, rewrite guards, compile."""

from hybrid.expr.parse import ExprError, Scope, parse_expression

__all__ = ["ExprError", "Scope", "parse_expression"]
