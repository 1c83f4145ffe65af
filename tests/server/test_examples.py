"""The shipped examples: every hub program in examples/ has its group and title, and an installed package
reads its own copy (setup.py puts the folder there)."""

import subprocess
import sys
from pathlib import Path

from openbricks_server import examples

ROOT = Path(__file__).resolve().parents[2]


def test_every_shipped_example_belongs_to_a_group_and_every_entry_to_a_file():
    shipped = {p.stem for p in examples.shipped_files(ROOT / "examples")}
    assert shipped == set(examples.CATALOGUE), (
        f"no CATALOGUE entry (group, title) for {sorted(shipped - set(examples.CATALOGUE))}; "
        f"entries without a file: {sorted(set(examples.CATALOGUE) - shipped)}"
    )
    groups = [group for group, _ in examples.GROUPS]
    assert {group for group, _ in examples.CATALOGUE.values()} == set(groups)  # no group left empty


def test_the_catalogue_is_grouped_in_the_manuals_order_with_a_summary_each():
    listed = examples.catalogue()
    assert [e.id for e in listed][:3] == ["first_robot", "motor_basics", "drivebase_square"]
    order = [group for group, _ in examples.GROUPS]
    assert [order.index(e.group) for e in listed] == sorted(order.index(e.group) for e in listed)
    assert all(e.summary and e.title and e.file == e.id + ".py" for e in listed)
    square = examples.find("drivebase_square")
    assert square.group_title == "Drive base" and square.summary.startswith("Drive a square")
    assert examples.source(square) == (ROOT / "examples" / "drivebase_square.py").read_text()


def test_an_installed_package_reads_the_copy_setup_py_puts_in_it(tmp_path):
    subprocess.run(
        [sys.executable, "setup.py", "-q", "build_py", "--build-lib", str(tmp_path)],
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    packaged = tmp_path / "openbricks_server" / "example_programs"
    assert {p.stem for p in examples.shipped_files(packaged)} == set(examples.CATALOGUE)
    assert not (packaged / "host").exists() and not (packaged / "manual").exists()
    found = subprocess.run(
        [sys.executable, "-c", "from openbricks_server import examples; print(examples.examples_dir())"],
        env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin"},
        cwd=tmp_path,
        check=True,
        capture_output=True,
        text=True,
    )
    assert Path(found.stdout.strip()) == packaged
