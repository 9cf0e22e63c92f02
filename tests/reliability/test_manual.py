"""The manual (docs/, built by ``make docs``): its options reference lists
every option ``-help`` lists, it links to nothing outside the repository,
and no page, heading or docstring narrates work steps or corrections."""
import functools
import os
import re
import subprocess
import sys

import pytest

from conftest import MPI_ENV, ROOT, read_text

#: words of a diary, not of a manual (case-sensitive where the word is also ordinary English)
DIARY = [re.compile(p) for p in (r"\b[Ss]tops? \d+", r"\bCorrection\b", r"\b[Ii]ssues? \d+", r"\bsessions?\b",
                                 r"\bwork steps?\b(?! or)", r"\bused to (be|run|give|say|exit|fail|crash)\b")]
#: where the manual's words live (CHANGELOG.md is the history, by design)
TEXTS = ("README.md", "docs", "petthm")


def _texts():
    for top in TEXTS:
        path = os.path.join(ROOT, top)
        if os.path.isfile(path):
            yield path
            continue
        for d, dirs, files in os.walk(path):
            dirs[:] = [x for x in dirs if x not in ("__pycache__", "_build")]
            yield from (os.path.join(d, f) for f in files if f.endswith((".md", ".py")))


def diary_lines(paths) -> list[str]:
    """The lines of ``paths`` that speak of work steps, issues, sessions or corrections."""
    out = []
    for path in paths:
        for n, line in enumerate(read_text(path).splitlines(), 1):
            if any(p.search(line) for p in DIARY):
                out.append(f"{os.path.relpath(path, ROOT)}:{n}: {line.strip()[:100]}")
    return out


def test_no_page_or_docstring_narrates_work_steps():
    assert diary_lines(_texts()) == []


def test_the_diary_check_finds_a_planted_line(tmp_path):
    """Negative control."""
    page = tmp_path / "page.md"
    page.write_text("# Results\n\nMeasured in stop 45: 12 Krylov iterations.\n")
    assert diary_lines([str(page)]) == [f"{os.path.relpath(page, ROOT)}:3: Measured in stop 45: 12 Krylov "
                                        "iterations."]


LINK = re.compile(r"\]\(([^)#\s]+)[^)]*\)|\{include\}\s+(\S+)")


def outside_links(paths) -> list[str]:
    """Links and includes of the pages that leave the repository, and
    mentions of the specifications outside it."""
    out = []
    for path in paths:
        text = read_text(path)
        for m in LINK.finditer(text):
            target = m.group(1) or m.group(2)
            if re.match(r"[a-z]+://", target):
                continue
            full = os.path.normpath(os.path.join(os.path.dirname(path), target))
            if not full.startswith(ROOT + os.sep):
                out.append(f"{os.path.relpath(path, ROOT)}: {target}")
        for spec in ("../shared", "physics.md", "verification.md", "paper.txt", "reservoir.md"):
            if spec in text:
                out.append(f"{os.path.relpath(path, ROOT)}: {spec}")
    return out


def _pages():
    for d, dirs, files in os.walk(os.path.join(ROOT, "docs")):
        dirs[:] = [x for x in dirs if x not in ("_build", "_ext")]
        yield from (os.path.join(d, f) for f in files if f.endswith(".md"))
    yield os.path.join(ROOT, "README.md")


def test_the_manual_links_to_nothing_outside_the_repository():
    assert outside_links(_pages()) == []


def test_the_link_check_finds_a_link_out(tmp_path):
    """Negative control: a page in the repository linking two levels up."""
    page = os.path.join(ROOT, "docs", "_planted_link_test.md")
    try:
        with open(page, "w") as f:
            f.write("See [the model](../../shared/docs/physics.md).\n")
        found = outside_links([page])
        assert found[0].endswith(": ../../shared/docs/physics.md") and len(found) == 3, found
    finally:
        os.remove(page)


@functools.cache
def _help_options() -> frozenset[str]:
    """Every -thm_* option that ``python -m petthm SCENE -help`` lists, over all scenes."""
    from petthm.scenes import MODULES
    found = set()
    env = dict(os.environ, **MPI_ENV)
    for scene in sorted(MODULES):
        out = subprocess.run([sys.executable, "-m", "petthm", scene, "-help"], cwd=ROOT, env=env,
                             capture_output=True, text=True, timeout=120).stdout
        found |= set(re.findall(r"^\s+(-thm_\w+)\s", out, re.M))
    return frozenset(found)


@pytest.mark.parametrize("plant", [False, True])
def test_the_options_reference_lists_every_option_help_lists(plant):
    """The reference (docs/_ext/petthm_options.py, from the option table)
    against ``-help`` of every scene; the negative control drops one option."""
    sys.path.insert(0, os.path.join(ROOT, "docs", "_ext"))
    import petthm_options
    listed = petthm_options.options() - ({"-thm_rock_conductivity"} if plant else set())
    helped = _help_options()
    assert len(helped) > 100 and (listed == helped) != plant, sorted(listed ^ helped)
