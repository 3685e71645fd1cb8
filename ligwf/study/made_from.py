"""What a record was made from: a content digest per field, so an edit is seen and named.

ligwf writes the study record (``study.json``) and each case's scene record
(``scene.json``) once, from a workflow; every later stage trusts them. A record carries
a seal (``made_from``): the SHA-256 of its content as written and a short digest of every
leaf field (``workflow.scene.liquid.surface_tension``, ``cases[2].cg``). On read the
content is digested again: equal, the record is the one ligwf wrote; different, the
fields whose digests differ are named (``cases[1].cg = 4.0``, ``workflow.sweep.seed
added``), so a hand edit is refused in one line naming the field instead of being run,
analysed or reported as if ligwf had written it (signac's rule: a different state point
is a different job, never the same one edited).

The seal detects edits by hand or by a tool that does not know it, not an attacker who
recomputes it (it is a digest, not a signature). A record without a seal (written before
seals existed) is read as before.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any, Mapping

#: the key of the seal in a record
SEAL_KEY = "made_from"
#: hex digits kept per field digest (48 bits: a hand edit never collides)
FIELD_DIGEST_HEX = 12
#: fields named in one message at most (the rest are counted)
SHOWN_FIELDS = 3


def _canonical(value: Any) -> str:
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=True)


def as_json(value: Any) -> Any:
    """``value`` as it reads back from JSON (tuples as lists, numeric keys as text): what
    a seal is computed from on write and on read alike."""
    return json.loads(_canonical(value))


def leaves(value: Any, prefix: str = "") -> dict[str, Any]:
    """Every leaf of a JSON value by its path (``a.b[2].c``); an empty mapping or list is a
    leaf of its own."""
    if isinstance(value, dict) and value:
        out: dict[str, Any] = {}
        for key, item in value.items():
            out.update(leaves(item, f"{prefix}.{key}" if prefix else str(key)))
        return out
    if isinstance(value, list) and value:
        out = {}
        for k, item in enumerate(value):
            out.update(leaves(item, f"{prefix}[{k}]"))
        return out
    return {prefix: value}


def _field_digest(value: Any) -> str:
    return hashlib.sha256(_canonical(value).encode()).hexdigest()[:FIELD_DIGEST_HEX]


def seal(content: Mapping[str, Any]) -> dict:
    """The seal of a record's ``content`` (the fields it covers, as written)."""
    content = as_json(dict(content))
    return {"sha256": hashlib.sha256(_canonical(content).encode()).hexdigest(),
            "fields": {path: _field_digest(v) for path, v in leaves(content).items()}}


def edited_fields(content: Mapping[str, Any], stored_seal: Any) -> list[str] | None:
    """The fields of ``content`` (as read) that differ from the ``stored_seal``, each as
    ``path = value`` (changed), ``path added`` or ``path removed``; [] when the content is
    the sealed one; None when there is no seal (an older record: nothing to compare) .
    A seal that is not one ligwf writes is itself an edit (``made_from``)."""
    if stored_seal is None:
        return None
    if not (isinstance(stored_seal, dict) and isinstance(stored_seal.get("sha256"), str)
            and isinstance(stored_seal.get("fields"), dict)):
        return [f"{SEAL_KEY} (not a seal ligwf writes)"]
    content = as_json(dict(content))
    if hashlib.sha256(_canonical(content).encode()).hexdigest() == stored_seal["sha256"]:
        return []
    now, then = leaves(content), stored_seal["fields"]
    changed = [f"{p} = {_short(now[p])}" for p in now if p in then
               and _field_digest(now[p]) != then[p]]
    added = [f"{p} added" for p in now if p not in then]
    removed = [f"{p} removed" for p in then if p not in now]
    return changed + added + removed or [f"{SEAL_KEY} (its digest was changed)"]


def _short(value: Any, limit: int = 40) -> str:
    text = _canonical(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def edit_summary(fields: list[str]) -> str:
    """The edited fields in one line: the first :data:`SHOWN_FIELDS`, then how many more."""
    shown = "; ".join(fields[:SHOWN_FIELDS])
    more = len(fields) - SHOWN_FIELDS
    return shown + (f" (and {more} more field(s))" if more > 0 else "")


def sealed(record: Mapping[str, Any], unsealed: tuple[str, ...] = ("ligwf_version",)) -> dict:
    """``record`` with its seal (:data:`SEAL_KEY`) over every field but ``unsealed``."""
    return {**record, SEAL_KEY: seal({k: v for k, v in record.items()
                                      if k not in unsealed and k != SEAL_KEY})}


def record_edits(record: Mapping[str, Any],
                 unsealed: tuple[str, ...] = ("ligwf_version",)) -> list[str] | None:
    """:func:`edited_fields` of a record :func:`sealed` wrote (None: it has no seal)."""
    return edited_fields({k: v for k, v in record.items()
                          if k not in unsealed and k != SEAL_KEY}, record.get(SEAL_KEY))
