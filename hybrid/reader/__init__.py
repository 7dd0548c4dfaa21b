"""Spec files: safe YAML with positions, pydantic schema, model building."""

from hybrid.reader.loader import load, load_document, load_text

__all__ = ["load", "load_document", "load_text"]
