"""What a scene value may be: safe strings, numbers that are numbers, physical floors.

The base of every parameter object (:class:`Frozen`: immutable, unknown keys refused,
finite numbers that are never text or a yes/no value, also inside lists and mappings) and
the checks the scene model's fields share (:mod:`ligwf.scene.model` and the other parameter
modules import them from here).
"""

from __future__ import annotations

import enum
import re
import types
import typing
import unicodedata
from typing import Annotated, Any, Literal

from pydantic import AfterValidator, BaseModel, ConfigDict, ValidationInfo, field_validator

from ligwf.scene.messages import ItemProblem


#: Characters that must never reach a LIGGGHTS input: a newline ends the command and starts
#: a new one, '&' continues a line, '$' expands variables, '#' starts a comment and quotes
#: group words. LIGGGHTS has a ``shell`` command, so an injected line could run anything.
FORBIDDEN_INPUT_CHARS = ("\n", "\r", "&", "$", "#", "'", '"')


def unsafe_chars(value: str) -> list[str]:
    """The characters of ``value`` that could inject or break a line of a LIGGGHTS input:
    :data:`FORBIDDEN_INPUT_CHARS` and every other control character (NUL, tab, DEL, C1...)."""
    bad = [c for c in FORBIDDEN_INPUT_CHARS if c in value]
    # C0, DEL and the C1 controls (U+0080-U+009F: invisible, and bytes 0x80-0x9F in a
    # Latin-1 terminal)
    return bad + sorted({c for c in value if unicodedata.category(c) == "Cc" and c not in bad})


def check_input_safe(value: str) -> str:
    """Refuse a string that could inject or break a line of a LIGGGHTS input."""
    bad = unsafe_chars(value)
    if bad:
        shown = ", ".join(repr(c) for c in bad)
        raise ValueError(f"contains {shown}; strings that reach the LIGGGHTS input may not "
                         "contain a newline, a control character, '&', '$', '#' or a quote")
    return value


SafeStr = Annotated[str, AfterValidator(check_input_safe)]

# Physical floors (SI): below them a value is a typo or a unit slip, and the derived times
# (Rayleigh time, steps) underflow or divide by zero.
#: m: smallest particle diameter, drum length or lifter height (1 um)
MIN_LENGTH = 1e-6
#: s: shortest run, dump, thermo or restart interval (1 us)
MIN_TIME = 1e-6
#: smallest restitution coefficient (LIGGGHTS damps with ln e)
MIN_RESTITUTION = 1e-3


def _members(annotation: Any) -> tuple[Any, ...]:
    """The alternatives of a union (``float | None``), unwrapping ``Annotated``."""
    if typing.get_origin(annotation) is Annotated:
        return _members(typing.get_args(annotation)[0])
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return tuple(m for a in typing.get_args(annotation) for m in _members(a))
    return (annotation,)


def _admits(annotation: Any, kinds: tuple[type, ...]) -> bool:
    """Whether a scalar of one of ``kinds`` may stand where ``annotation`` is."""
    for member in _members(annotation):
        if typing.get_origin(member) is Literal:
            if any(isinstance(a, kinds) for a in typing.get_args(member)):
                return True
        elif isinstance(member, type) and (
                (issubclass(member, kinds) and (member is not bool or bool in kinds))
                or (str in kinds and issubclass(member, enum.Enum))):
            return True
        elif member is Any:
            return True
    return False


_BASE60 = re.compile(r"[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+(?:\.[0-9_]*)?")
_LEADING_ZERO = re.compile(r"[-+]?0[0-9_]+")
_NOT_DECIMAL = re.compile(r"[-+]?0[xXoObB][0-9a-fA-F_]+")
_YAML11_WORDS = {"yes", "no", "on", "off", "y", "n"}


def _text_for_number(text: str) -> str:
    """Why ``text`` (a string where a number belongs) is refused, and what to write."""
    why = "a number is expected, not text"
    word = text.strip()
    if _BASE60.fullmatch(word):
        sign, digits = (-1, word[1:]) if word[0] == "-" else (1, word.lstrip("+"))
        total = 0.0
        for part in digits.replace("_", "").split(":"):
            total = 60 * total + float(part)
        return (f"{why}: YAML 1.1 would read {word} as the base-60 number {sign * total:g}; "
                "write the number you mean")
    if word.lower() in _YAML11_WORDS:
        return f"{why}: {word!r} is a YAML 1.1 yes/no word, not a number"
    if _LEADING_ZERO.fullmatch(word):
        return f"{why}: YAML 1.1 would read the leading zero as octal; write it without the 0"
    if _NOT_DECIMAL.fullmatch(word):
        return f"{why}: write the number in decimal"
    try:
        float(word)
    except ValueError:
        return why
    return f"{why}: write {word} without quotes"


def scalar_problem(value: Any, annotation: Any,
                   where: tuple[Any, ...] = ()) -> ItemProblem | None:
    """Why ``value`` may not stand where ``annotation`` is, looking into lists and mappings
    (``cg_levels: [true]`` names ``cg_levels[0]``), or None. Pydantic's lax mode would read
    ``true`` as 1 and ``"2500"`` as 2500; a workflow says what it means."""
    numbers = (int, float)
    if isinstance(value, bool):
        if _admits(annotation, (bool,)) or not _admits(annotation, numbers):
            return None
        return ItemProblem(where, value, f"{str(value).lower()} is a yes/no value; a number "
                           "is expected")
    if isinstance(value, str):
        if _admits(annotation, (str,)) or not _admits(annotation, numbers):
            return None
        return ItemProblem(where, value, _text_for_number(value))
    if isinstance(value, (list, tuple)):
        for member in _members(annotation):
            args = typing.get_args(member)
            if typing.get_origin(member) in (tuple, list) and args:
                items = (args[0],) * len(value) if len(args) == 1 or args[1:] == (...,) else args
                for k, (item, ann) in enumerate(zip(value, items)):
                    problem = scalar_problem(item, ann, (*where, k))
                    if problem:
                        return problem
    if isinstance(value, dict):
        for member in _members(annotation):
            args = typing.get_args(member)
            if typing.get_origin(member) is dict and len(args) == 2:
                for key, item in value.items():
                    problem = (scalar_problem(key, args[0], (*where, key))
                               or scalar_problem(item, args[1], (*where, key)))
                    if problem:
                        return problem
    return None


class Frozen(BaseModel):
    """Base of all parameter objects: immutable, unknown keys are errors (typos), numbers
    are finite, never a YAML ``true``/``false`` (pydantic would read true as 1.0) and never
    text (pydantic would read "2500" as 2500)."""

    model_config = ConfigDict(frozen=True, extra="forbid", validate_default=True,
                              allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _numbers_are_numbers(cls, value: Any, info: ValidationInfo) -> Any:
        field = cls.model_fields.get(info.field_name) if info.field_name else None
        problem = scalar_problem(value, field.annotation) if field is not None else None
        if problem:
            raise problem
        return value


def zero_or_at_least(floor: float, most: float, unit: str):
    """AfterValidator: 0 (the effect switched off) or a value in [floor, most]; a positive
    value below ``floor`` is physically zero and numerically a trap (1e-300 N/m)."""
    def check(value: float) -> float:
        if 0.0 < value < floor:
            raise ValueError(f"below the physical floor (allowed: 0 to switch it off, or "
                             f"the range [{floor:g}, {most:g}] {unit})")
        return value
    return AfterValidator(check)
