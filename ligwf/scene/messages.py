"""Validation messages: pydantic's errors as ``field = value: reason (allowed range ...)``.

One line per problem, with the full dotted path a user writes in a workflow or a ``--set``,
the value as given and the declared bounds of the field, so a refusal says what to change.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ValidationError


def short_repr(value: Any) -> str:
    """``repr(value)`` cut to 60 characters: a refusal names the value without pasting a
    whole list or mapping into the message."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


_BOUND_WORDS = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}


def _allowed_range(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> str | None:
    """The full interval of a numeric field, e.g. '(0, 0.7]', from its declared bounds."""
    field = None
    for part in loc:
        if isinstance(part, int):  # index into a tuple of models: same element model
            continue
        if model is None or part not in model.model_fields:
            return None
        field = model.model_fields[part]
        ann = field.annotation
        nxt = None
        for cand in getattr(ann, "__args__", (ann,)):
            if isinstance(cand, type) and issubclass(cand, BaseModel):
                nxt = cand
            for sub in getattr(cand, "__args__", ()):
                if isinstance(sub, type) and issubclass(sub, BaseModel):
                    nxt = sub
        model = nxt
    if field is None:
        return None
    bounds: dict[str, float] = {}
    for meta in field.metadata:
        for key in _BOUND_WORDS:
            val = getattr(meta, key, None)
            if val is not None:
                bounds[key] = val
    if not bounds:
        return None
    lo = f"({bounds['gt']:g}" if "gt" in bounds else (f"[{bounds['ge']:g}" if "ge" in bounds
                                                     else "(-inf")
    hi = f"{bounds['lt']:g})" if "lt" in bounds else (f"{bounds['le']:g}]" if "le" in bounds
                                                     else "inf)")
    return f"{lo}, {hi}"


def format_validation_error(exc: ValidationError, root: type[BaseModel], prefix: str) -> str:
    """One line per problem: ``field = value: reason (allowed: range)``."""
    lines = []
    errors = exc.errors()
    deeper = {tuple(e["loc"][:-1]) for e in errors if len(e["loc"]) > 1}
    for err in errors:
        loc = tuple(err["loc"])
        if err["type"] == "too_short" and any(d[:len(loc)] == loc for d in deeper):
            continue  # a collection emptied by its own invalid items: already reported
        path = ".".join(str(p) for p in (prefix, *loc) if p != "")
        value = err.get("input")
        msg = err["msg"].removeprefix("Value error, ")
        if err["type"] == "extra_forbidden":
            lines.append(f"{path}: unknown key (typo?)")
            continue
        if err["type"] == "missing":
            lines.append(f"{path}: required field is missing")
            continue
        line = f"{path} = {short_repr(value)}: {msg}"
        rng = _allowed_range(root, loc)
        if rng:
            line += f" (allowed range {rng})"
        lines.append(line)
    return "\n".join(lines)
