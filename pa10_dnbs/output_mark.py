"""The mark by which a folder is known as a pa10-dnbs output (a run's outputs, a recorded bag): ``--force`` replaces
only an empty folder or one holding it (report/outputs.py check_output_dir, bag/bag_writer.py check_bag_path)."""
from __future__ import annotations

from pathlib import Path

# A file name such as report.md or metadata.yaml at a folder's top is no proof (a thesis folder may hold one).
OUTPUT_MARK = ".pa10-dnbs-output"
OUTPUT_MARK_TEXT = ("Written by pa10-dnbs: this folder is a pa10-dnbs output; a later run with --force replaces "
                    "the folder whole.\n")


def is_previous_output(out: Path) -> bool:
    """``out`` holds a pa10-dnbs command's output: OUTPUT_MARK at its top (a file, not a link)."""
    mark = Path(out) / OUTPUT_MARK
    return mark.is_file() and not mark.is_symlink()
