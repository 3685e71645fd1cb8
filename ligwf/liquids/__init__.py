"""Liquid models, one module each, and their registry.

Every stage that depends on the liquid (scene validation, scaling, rendering, pre-flight,
granule analysis) asks :func:`get` for the scene's model instead of comparing names, so a
new capillary law is one new module (a :class:`~ligwf.liquids.base.LiquidModel`) and one
:func:`register` call; its own settings are a class it declares (``settings_type``), so a
new parameter needs no edit elsewhere either. Built in: ``washino``, ``easo`` and ``none``
(dry).
"""

from __future__ import annotations

from ligwf.liquids.base import LiquidModel
from ligwf.liquids.dry import DRY
from ligwf.liquids.easo import EASO
from ligwf.liquids.washino import WASHINO

_MODELS: dict[str, LiquidModel] = {}


def register(model: LiquidModel) -> LiquidModel:
    """Make ``model`` available under ``model.name`` (again for the same object: a no-op)."""
    known = _MODELS.get(model.name)
    if known is not None and known is not model:
        raise ValueError(f"liquid model {model.name!r} is already registered")
    _MODELS[model.name] = model
    return model


def names() -> tuple[str, ...]:
    """Registered model names, sorted."""
    return tuple(sorted(_MODELS))


def get(name: str) -> LiquidModel:
    """The model registered as ``name``; ValueError naming the allowed ones otherwise."""
    try:
        return _MODELS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown liquid model {name!r} (allowed: {', '.join(names())})") \
            from None


def setting_owners() -> dict[str, tuple[str, ...]]:
    """Every registered model's own settings (``LiquidModel.settings_type``) by key: the
    names of the models that have it, sorted. What the scene refuses for another model and
    the foreign-dump reader offers as options."""
    owners: dict[str, list[str]] = {}
    for name in names():
        for key in _MODELS[name].settings_type.model_fields:
            owners.setdefault(key, []).append(name)
    return {key: tuple(models) for key, models in owners.items()}


for _model in (WASHINO, EASO, DRY):
    register(_model)
