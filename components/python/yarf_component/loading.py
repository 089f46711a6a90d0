"""Finding component classes from the command line's TARGETs.

A TARGET is ``package.module:ClassName`` or ``path/to/file.py:ClassName``;
without ``:ClassName`` it names every component class the module defines.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
from pathlib import Path
from types import ModuleType

from yarf_component.component import Component


class TargetError(ValueError):
    """A TARGET that names no module or no component class."""


def _module_name(path: Path) -> str:
    """The file's stem, unless another module (e.g. an installed package) has that name."""
    stem = re.sub(r"\W", "_", path.stem)
    if not stem.isidentifier():
        stem = f"_{stem}"
    loaded = sys.modules.get(stem)
    if loaded is not None:
        taken = getattr(loaded, "__file__", None) != str(path)
    else:
        try:
            spec = importlib.util.find_spec(stem)
        except (ImportError, ValueError):
            spec = None
        taken = spec is not None and spec.origin != str(path)
    if not taken:
        return stem
    return f"{stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:8]}"


def _load_file(path: Path) -> ModuleType:
    if not path.is_file():
        raise TargetError(f"no file {path}")
    path = path.resolve()
    name = _module_name(path)
    loaded = sys.modules.get(name)
    if loaded is not None:
        # Loaded already (e.g. by a file that subclasses its classes): one copy.
        return loaded
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise TargetError(f"cannot load {path} as Python")
    module = importlib.util.module_from_spec(spec)
    # Registered before it runs, so that its dataclasses and annotations
    # resolve; its folder on the path (last: installed modules keep their
    # names), so that it can import the files beside it.
    sys.modules[name] = module
    if str(path.parent) not in sys.path:
        sys.path.append(str(path.parent))
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[name]
        raise
    return module


def _load_module(target: str) -> ModuleType:
    if target.endswith(".py") or "/" in target or "\\" in target:
        return _load_file(Path(target))
    try:
        return importlib.import_module(target)
    except ModuleNotFoundError as error:
        raise TargetError(f"no module {target}: {error}") from None


def load_target(target: str) -> list[type[Component]]:
    """The classes ``target`` names."""
    module_part, _, class_part = target.rpartition(":") if ":" in target else (target, "", "")
    if not module_part:
        raise TargetError(f"'{target}' names no module: write module:Class or file.py:Class")
    module = _load_module(module_part)
    if class_part:
        cls = getattr(module, class_part, None)
        if cls is None:
            raise TargetError(f"{module_part} has no {class_part}")
        return [cls]
    found = [
        value
        for value in vars(module).values()
        if inspect.isclass(value)
        and issubclass(value, Component)
        and value.__module__ == module.__name__
        and "class_name" in value.__dict__
    ]
    if not found:
        raise TargetError(f"{module_part} defines no component class")
    return found
