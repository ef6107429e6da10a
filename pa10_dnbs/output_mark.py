"""The mark by which a folder is known as a pa10-dnbs output (a run's outputs, a recorded bag): ``--force`` replaces
only an empty folder or one holding it (report/outputs.py check_output_dir, bag/bag_writer.py check_bag_path)."""
from __future__ import annotations

from pathlib import Path

# A file name such as report.md or metadata.yaml at a folder's top is no proof (a thesis folder may hold one).
OUTPUT_MARK = ".pa10-dnbs-output"
OUTPUT_MARK_TEXT = ("Written by pa10-dnbs: this folder is a pa10-dnbs output; a later run with --force replaces "
                    "the folder whole.\n")


def is_previous_output(out: Path) -> bool:
    """``out`` holds a pa10-dnbs command's output: OUTPUT_MARK at its top (a file, not a link), or it is a bag
    recorded before bags carried the mark (:func:`is_unmarked_bag_of_ours`)."""
    mark = Path(out) / OUTPUT_MARK
    return (mark.is_file() and not mark.is_symlink()) or is_unmarked_bag_of_ours(Path(out))


MCAP_MAGIC = b"\x89MCAP0\r\n"
MCAP_HEADER_OP = 0x01


def is_unmarked_bag_of_ours(folder: Path) -> bool:
    """``folder`` holds exactly ``metadata.yaml`` and ``<folder name>.mcap``, and that MCAP file's Header record names
    pa10_dnbs as its writer (``library``): a bag this project recorded before it marked its bags (runs/main_bag of
    an earlier ``scripts/run_main.sh``), which ``--force`` may replace like a marked one."""
    mcap = folder / f"{folder.name}.mcap"
    try:
        if folder.is_symlink() or {f.name for f in folder.iterdir()} != {"metadata.yaml", mcap.name}:
            return False
        if mcap.is_symlink() or not mcap.is_file():
            return False
        with open(mcap, "rb") as fh:
            head = fh.read(8 + 1 + 8 + 4 + 256)
    except OSError:
        return False
    if not head.startswith(MCAP_MAGIC) or len(head) < 21 or head[8] != MCAP_HEADER_OP:
        return False
    n_profile = int.from_bytes(head[17:21], "little")
    at = 21 + n_profile
    n_library = int.from_bytes(head[at:at + 4], "little") if len(head) >= at + 4 else 0
    return head[at + 4:at + 4 + n_library].startswith(b"pa10_dnbs")
