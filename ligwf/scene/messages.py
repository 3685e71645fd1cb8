"""Validation messages: pydantic's errors as ``field = value: reason (allowed range ...)``.

One line per problem, with the full dotted path a user writes in a workflow or a ``--set``,
the value as given and the declared bounds of the field, so a refusal says what to change.
"""

from __future__ import annotations

import re
from typing import Any

from pydantic import BaseModel, ValidationError


def short_repr(value: Any) -> str:
    """``repr(value)`` cut to 60 characters: a refusal names the value without pasting a
    whole list or mapping into the message."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class ItemProblem(ValueError):
    """A field validator's refusal of one item of the field's value (``where``: indices or
    keys below the field, () for the value itself), so the message names
    ``sweep.cg_levels[0]``, not the whole list."""

    def __init__(self, where: tuple[Any, ...], value: Any, reason: str) -> None:
        super().__init__(reason)
        self.where, self.value = tuple(where), value


_BOUND_WORDS = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
#: pydantic's name of a union member in an error location ('int', 'dict[float,int]'):
#: not a field a user writes, so left out of the path
_UNION_TAG = re.compile(r"(int|float|str|bool|none|[a-z-]+\[.*\])")


def _clean_loc(loc: tuple[Any, ...]) -> tuple[Any, ...]:
    return tuple(p for p in loc if not (isinstance(p, str) and _UNION_TAG.fullmatch(p)))


def field_path(prefix: str, loc: tuple[Any, ...]) -> str:
    """``scene.particles.size_distribution[0].diameter``: dotted names, [i] for items."""
    path = prefix
    for part in loc:
        if isinstance(part, int) and not isinstance(part, bool):
            path += f"[{part}]"
        else:
            path = f"{path}.{part}" if path else str(part)
    return path


def _submodel(annotation: Any) -> type[BaseModel] | None:
    for cand in getattr(annotation, "__args__", (annotation,)):
        if isinstance(cand, type) and issubclass(cand, BaseModel):
            return cand
        for sub in getattr(cand, "__args__", ()):
            if isinstance(sub, type) and issubclass(sub, BaseModel):
                return sub
    return None


def _walk(model: type[BaseModel] | None, loc: tuple[Any, ...]):
    """(field info of the last name of ``loc``, the model that name leads to); None when
    ``loc`` leaves the models."""
    field = None
    for part in loc:
        if isinstance(part, int):  # index into a tuple of models: same element model
            continue
        if model is None or part not in model.model_fields:
            return None, None
        field = model.model_fields[part]
        model = _submodel(field.annotation)
    return field, model


def _model_at(root: type[BaseModel], loc: tuple[Any, ...]) -> type[BaseModel] | None:
    return root if not loc else _walk(root, loc)[1]


def _allowed_range(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> str | None:
    """The full interval of a numeric field, e.g. '(0, 0.7]', from its declared bounds."""
    field = _walk(model, loc)[0]
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
    show = {k: str(v) if isinstance(v, int) else f"{v:g}" for k, v in bounds.items()}
    lo = f"({show['gt']}" if "gt" in show else (f"[{show['ge']}" if "ge" in show else "(-inf")
    hi = f"{show['lt']})" if "lt" in show else (f"{show['le']}]" if "le" in show else "inf)")
    return f"{lo}, {hi}"


def _bound_reason(model: type[BaseModel] | None, loc: tuple[Any, ...]) -> str | None:
    """Why a field has its bounds (``json_schema_extra={"bound_reason": ...}``)."""
    field = _walk(model, loc)[0]
    extra = getattr(field, "json_schema_extra", None)
    return extra.get("bound_reason") if isinstance(extra, dict) else None


def range_note(model: type[BaseModel] | None, loc: tuple[Any, ...], msg: str,
               error_type: str) -> str:
    """What a refusal line adds after the message of an error of the field at ``loc`` of
    ``model``: its allowed range (unless the message states one) and, when the value broke
    a bound, why the bound is there; "" for a field without bounds."""
    rng = _allowed_range(model, loc) if "allowed" not in msg else None
    if not rng:
        return ""
    note = f" (allowed range {rng})"
    reason = _bound_reason(model, loc)
    if reason and error_type in ("less_than", "less_than_equal", "greater_than",
                                 "greater_than_equal"):
        note += f": {reason}"
    return note


_LEADING_FIELD = re.compile(r"([A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*)(?= = |: )")


def _model_level(root: type[BaseModel], loc: tuple[Any, ...], prefix: str, msg: str) -> str:
    """A model validator's message on the model at ``loc``: when it starts with one of the
    model's fields (``lifters.height = 0.03: ...``) the path is that field's, else the
    model's (``scene.process.rotation: give exactly one of rpm or froude``); never the
    model's whole input."""
    model = _model_at(root, loc)
    head = _LEADING_FIELD.match(msg)
    if model is not None and head:
        sub = tuple(head.group(1).split("."))
        if _walk(model, sub)[0] is not None:
            line = field_path(prefix, loc + sub) + msg[head.end():]
            rng = _allowed_range(root, loc + sub)
            if rng and "allowed" not in msg:
                line += f" (allowed range {rng})"
            return line
    return f"{field_path(prefix, loc)}: {msg}"


def format_validation_error(exc: ValidationError, root: type[BaseModel], prefix: str) -> str:
    """One line per problem: ``field = value: reason (allowed range ...)``."""
    lines: list[str] = []
    errors = exc.errors()
    deeper = {_clean_loc(tuple(e["loc"]))[:-1] for e in errors if len(e["loc"]) > 1}
    for err in errors:
        loc = _clean_loc(tuple(err["loc"]))
        if err["type"] == "too_short" and any(d[:len(loc)] == loc for d in deeper):
            continue  # a collection emptied by its own invalid items: already reported
        value = err.get("input")
        msg = err["msg"].removeprefix("Value error, ").removeprefix("Assertion failed, ")
        # a workflow has lists, not tuples (pydantic names the Python type)
        msg = msg.replace("a valid tuple", "a list")
        item = (err.get("ctx") or {}).get("error")
        if isinstance(item, ItemProblem):
            loc, value, msg = loc + item.where, item.value, str(item)
        path = field_path(prefix, loc)
        if err["type"] == "extra_forbidden":
            line = f"{path}: unknown key (typo?)"
        elif err["type"] == "missing":
            line = f"{path}: required field is missing"
        elif err["type"] in ("value_error", "assertion_error") and isinstance(value, dict) \
                and _model_at(root, loc) is not None:
            line = _model_level(root, loc, prefix, msg)
        else:
            line = f"{path} = {short_repr(value)}: {msg}" + range_note(root, loc, msg,
                                                                       err["type"])
        if line not in lines:
            lines.append(line)
    return "\n".join(lines)
