"""A newcomer's first minutes (docs/user-guide/reliability.md, "Newcomer"): the
README's commands after ``make demo``, copied as written into a fresh
shell (the activation line, then the "Running" block), and every
verification scene's errors against its reference printed at the end."""
import os
import re
import subprocess

import pytest

from conftest import MPI_ENV, ROOT, read_text, run_petthm


def _block_after(text: str, marker: str) -> str:
    """The first ```sh block after ``marker``."""
    rest = text[text.index(marker):]
    return re.search(r"```sh\n(.*?)```", rest, re.S).group(1)


def test_the_readmes_commands_work_in_a_fresh_shell(tmp_path):
    readme = read_text(os.path.join(ROOT, "README.md"))
    activate = _block_after(readme, "Then put petthm on your shell")
    running = _block_after(readme, "## Running\n")
    assert activate.strip().startswith("source .venv/bin/activate")
    for name in (".venv", "options", "meshes"):         # the petthm folder, without earlier output
        os.symlink(os.path.join(ROOT, name), tmp_path / name)
    env = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": os.environ.get("HOME", "/root"), **MPI_ENV}
    script = "set -eo pipefail\n" + activate + running
    proc = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "scenes:" in proc.stdout and "parameters (-option" in proc.stdout
    assert proc.stdout.count("completed: t = ") == 3, proc.stdout
    assert "Traceback" not in proc.stderr


#: every scene with a reference solution, with fast settings (the restart test
#: tests/reliability/test_restart_consistency.py covers the others: WHOLE_RUN)
PRINTS_ERRORS = {
    "coupled_mms": ("-ts_max_steps", 1, "-thm_fe_degree", 1),
    "heat_mms": ("-thm_fe_degree", 1),
    "heat_erfc": ("-thm_final_time", 1e4),
    "fracture_flow_patch": (),
    "radial_flow": ("-thm_fe_degree", 1),
    "leakoff_heat": ("-thm_fe_degree", 1, "-thm_mesh_size", 20, "-thm_leakoff_heat_fracture_size", 2),
    "gravity_column": (),
    "sneddon": ("-thm_sneddon_dim", 2, "-thm_fe_degree", 1),
    "inclined_crack": ("-thm_fe_degree", 1),
}
#: the scenes without a reference solution: the paper's scenes, partial_opening (its active set) and
#: reservoir (a user's deck; its decks against exact results: tests/verification/test_reservoir.py)
NO_REFERENCE = {"rigid_fracture", "penny_impermeable", "inclined_penny", "partial_opening", "reservoir"}


@pytest.mark.parametrize("scene", sorted(PRINTS_ERRORS))
def test_every_verification_scene_prints_its_errors_at_the_end(tmp_path, scene):
    from test_restart_consistency import WHOLE_RUN

    from petthm.scenes import all_scenes
    assert set(all_scenes()) - NO_REFERENCE == set(PRINTS_ERRORS) | {k.split("[")[0] for k in WHOLE_RUN}
    proc, s = run_petthm(scene, tmp_path, *PRINTS_ERRORS[scene], check=False)
    assert proc.returncode in (0, 4), proc.stderr
    line = next(x for x in proc.stdout.splitlines() if x.startswith("errors against the reference: "))
    assert all(f"{k} " in line for k, v in s["error"].items() if v is not None), (line, s["error"])
