"""The README's commands after ``make demo``, copied as written into a
fresh shell: the activation line, then the "Running" block (a test of the
newcomer's first minutes: docs/reliability.md, "Newcomer")."""
import os
import re
import subprocess

from conftest import MPI_ENV, ROOT


def _block_after(text: str, marker: str) -> str:
    """The first ```sh block after ``marker``."""
    rest = text[text.index(marker):]
    return re.search(r"```sh\n(.*?)```", rest, re.S).group(1)


def test_the_readmes_commands_work_in_a_fresh_shell(tmp_path):
    readme = open(os.path.join(ROOT, "README.md")).read()
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
