"""The options reference of the manual, generated from petthm's one option
table (the declarations ``-help`` lists): the directive ``petthm-options``
renders every ``-thm_*`` option with its unit, kind, accepted range,
meaning and default, grouped as run control, physical parameters (with the
scenes that use each) and each scene's own options."""
from __future__ import annotations

import dataclasses

from docutils import nodes
from docutils.parsers.rst import Directive
from docutils.statemachine import StringList


def _default_text(f) -> str:
    d = f.default
    if isinstance(d, tuple):
        d = ",".join(map(str, d))
    return f"{d:g}" if isinstance(d, float) else str(d)


def groups() -> list[tuple[str, list[dict]]]:
    """[(title, [row])]: a row has option, default, unit, kind, range, help, scenes."""
    from petthm import params as P
    from petthm.physics.materials import DECLARED
    from petthm.scenes import all_scenes

    def row(f, default=None, scenes=()):
        md = f.metadata
        has_range = md.get("lo") is not None or md.get("hi") is not None or md.get("choices")
        return {"option": "-" + P.option_name(f), "default": default or _default_text(f), "unit": md["unit"],
                "kind": md["kind"], "range": P._range_text(md) if has_range else "",
                "help": md["help"], "scenes": ", ".join(sorted(scenes))}
    run = [row(f) for f in dataclasses.fields(P.RunParams)]
    users: dict[str, dict] = {}
    own: dict[str, list] = {}
    for name, cls in sorted(all_scenes().items()):
        for f in dataclasses.fields(P.merged(cls.parameters)):
            if f.name in DECLARED:
                users.setdefault(f.name, {})[name] = _default_text(f)
            else:
                own.setdefault(name, []).append(row(f))
    physical = []
    for name, f in DECLARED.items():
        defaults = users.get(name, {})
        shown = sorted(set(defaults.values()))
        physical.append(row(_named(f, name), default=" / ".join(shown) if shown else _default_text(f),
                            scenes=defaults))
    out = [("Run control (every scene)", run), ("Physical parameters", physical)]
    out += [(f"Scene {name}", rows) for name, rows in sorted(own.items())]
    return out


def _named(f, name):
    """A copy of a declaration that knows its option name (``DECLARED`` holds unnamed fields)."""
    g = dataclasses.field(default=f.default, metadata=f.metadata)
    g.name = name
    return g


def options() -> set[str]:
    """Every option the reference lists."""
    return {r["option"] for _, rows in groups() for r in rows}


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ") or " "


class OptionsDirective(Directive):
    has_content = False

    def run(self):
        lines = []
        for title, rows in groups():
            scenes = title == "Physical parameters"
            lines += [f".. rubric:: {title}", "", ".. list-table::", "   :header-rows: 1",
                      "   :widths: " + ("22 10 8 10 10 28 12" if scenes else "24 10 8 10 12 36"), "",
                      "   * - option", "     - default", "     - unit", "     - kind", "     - range",
                      "     - meaning"] + (["     - scenes"] if scenes else [])
            for r in rows:
                lines += [f"   * - ``{r['option']}``", f"     - {_cell(r['default'])}",
                          f"     - {_cell(r['unit'])}", f"     - {r['kind']}", f"     - {_cell(r['range'])}",
                          f"     - {_cell(r['help'])}"]
                if scenes:
                    lines.append(f"     - {_cell(r['scenes'])}")
            lines.append("")
        node = nodes.section()
        node.document = self.state.document
        self.state.nested_parse(StringList(lines), self.content_offset, node)
        return node.children


class ScenesDirective(Directive):
    """The table of scenes (``petthm-scenes``): name, what it is (the scene's
    ``description``), its options file, its space dimension."""
    has_content = False

    def run(self):
        import os

        from petthm.scenes import all_scenes
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        lines = [".. list-table::", "   :header-rows: 1", "   :widths: 18 56 26", "",
                 "   * - scene", "     - what it is", "     - options file"]
        for name, cls in sorted(all_scenes().items()):
            opts = f"options/scenes/{name}.opts"
            lines += [f"   * - ``{name}``", f"     - {_cell(cls.description)}",
                      f"     - ``{opts}``" if os.path.isfile(os.path.join(root, opts)) else "     - "]
        node = nodes.section()
        node.document = self.state.document
        self.state.nested_parse(StringList(lines), self.content_offset, node)
        return node.children


def setup(app):
    app.add_directive("petthm-options", OptionsDirective)
    app.add_directive("petthm-scenes", ScenesDirective)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
