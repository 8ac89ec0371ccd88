"""Help text built from :class:`floewave.ModelConfig` itself, so it cannot go stale.

``floewave run --help`` lists every field with its type, default, units and meaning as
read from the dataclass fields and the class docstring (a field added there appears
here); :func:`did_you_mean` suggests a field for a misspelt name.
"""
from __future__ import annotations

import dataclasses
import difflib
import re
import textwrap

from .config import ModelConfig

__all__ = ["FieldDoc", "field_docs", "fields_help", "did_you_mean"]

_ENTRY = re.compile(r"^([A-Za-z_]\w*(?:\s*,\s*[A-Za-z_]\w*)*)\s+:\s+(.*)$")
_UNITS = re.compile(r"\[([^\]]*)\]")


@dataclasses.dataclass(frozen=True)
class FieldDoc:
    """One ModelConfig field: name, type name, default, units ('' if not documented) and
    its description from the class docstring."""

    name: str
    type: str
    default: object
    units: str
    description: str


def _docstring_entries(doc: str) -> dict[str, tuple[str, tuple[str, ...]]]:
    """``name : description`` entries of a NumPy-style docstring (``a, b : …`` and several
    entries on one line separated by ``;`` included), continuation lines joined."""
    entries: list[str] = []
    for line in doc.splitlines():
        if not line.strip() or set(line.strip()) <= {"-"}:
            continue
        indent = len(line) - len(line.lstrip())
        if indent > 4 and entries:
            entries[-1] += " " + line.strip()
        else:
            entries.append(line.strip())
    out: dict[str, tuple[str, tuple[str, ...]]] = {}
    for entry in entries:
        # "h : water depth [m]; L_y : floe width [m]" -> two entries
        parts = re.split(r";\s+(?=[A-Za-z_]\w*(?:\s*,\s*[A-Za-z_]\w*)*\s+:\s)", entry)
        for part in parts:
            m = _ENTRY.match(part)
            if m:
                names = tuple(n.strip() for n in m.group(1).split(","))
                for name in names:
                    out.setdefault(name, (m.group(2).strip(), names))
    return out


def _units(name: str, text: str, names: tuple[str, ...]) -> str:
    """The units of ``name`` in its entry: ``[..]`` right after the name, else by position
    (``a, b : … [-], [m]``), else the entry's one ``[..]``."""
    own = re.search(rf"``{re.escape(name)}`` \[([^\]]*)\]", text)
    if own:
        return own.group(1)
    found = _UNITS.findall(text)
    if len(names) > 1 and len(found) == len(names):
        return found[names.index(name)]
    named = [n for n in names if re.search(rf"``{re.escape(n)}`` \[", text)]
    if len(found) == 1 and not named:
        return found[0]
    return ""


def field_docs() -> list[FieldDoc]:
    """Every ModelConfig field in declaration order, documented from its docstring."""
    doc = ModelConfig.__doc__ or ""
    entries = _docstring_entries(doc)
    out = []
    for f in dataclasses.fields(ModelConfig):
        text, names = entries.get(f.name, ("", (f.name,)))
        type_name = f.type if isinstance(f.type, str) else f.type.__name__
        if type_name in ("bool", "str"):
            units = ""
        elif text:
            units = _units(f.name, text, names)
        else:  # "...; c_ow [-], s_min [-]": units written after the field's name
            m = re.search(rf"\b{re.escape(f.name)} \[([^\]]*)\]", doc)
            units = m.group(1) if m else ""
            if m:
                text = next((t for t, _ in entries.values() if f"{f.name} [" in t), "")
        out.append(FieldDoc(f.name, type_name, f.default, units, text))
    return out


def fields_help(width: int = 100) -> str:
    """The ``floewave run --help`` epilog: one block per field."""
    lines = ["fields (NAME = default [units]: meaning; set with --set NAME=VALUE):"]
    for d in field_docs():
        default = str(d.default).lower() if isinstance(d.default, bool) else repr(d.default)
        head = f"  {d.name} = {default}" + (f" [{d.units}]" if d.units else "") + f" ({d.type})"
        desc = d.description or "(see help(floewave.ModelConfig))"
        lines.append(head)
        lines += textwrap.wrap(desc, width=width, initial_indent="      ",
                               subsequent_indent="      ")
    return "\n".join(lines)


def did_you_mean(name: str) -> str:
    """`` (did you mean 'eps'?)`` for a misspelt field name, or ``''``."""
    names = [f.name for f in dataclasses.fields(ModelConfig)]
    lower = {n.lower(): n for n in names}
    close = difflib.get_close_matches(name.lower(), list(lower), n=3, cutoff=0.6)
    close += [lower[n] for n in lower if len(n) >= 2 and name.lower().startswith(n)
              and lower[n] not in close]
    close = [lower.get(c, c) for c in close]
    return f" (did you mean {' or '.join(repr(c) for c in dict.fromkeys(close))}?)" \
        if close else ""
