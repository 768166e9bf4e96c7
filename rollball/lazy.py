"""Public names of a package imported when first used (PEP 562), not with the package: so that
``import rollball.cli`` loads nothing numerical and the command line answers at once."""

from __future__ import annotations

import sys
from importlib import import_module


def lazy_names(package: str, names: dict[str, str]):
    """The ``__getattr__`` and ``__dir__`` of ``package``, whose public ``names`` (each with the
    module below the package that defines it) are imported on first use, then kept."""

    def __getattr__(name: str):
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(f"{package}.{module}"), name)
        setattr(sys.modules[package], name, value)   # looked up once
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__
