"""make gradescope: the Gradescope autograder zip. This checkout's committed tree (git archive of
HEAD), with setup.sh and run_autograder at its root, where Gradescope looks for them.

Usage: /usr/bin/python3 scripts/gradescope/zip.py OUT.zip
"""
import io
import subprocess
import sys
import zipfile
from pathlib import Path

HERE = Path(__file__).parent


def main(out: str) -> int:
    tree = subprocess.run(["git", "archive", "--format=zip", "HEAD"], check=True,
                          capture_output=True, cwd=HERE.parent.parent).stdout
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(io.BytesIO(tree)) as source, \
            zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zip_out:
        for item in source.infolist():
            zip_out.writestr(item, source.read(item))
        for name in ("setup.sh", "run_autograder"):
            entry = zipfile.ZipInfo(name)
            entry.external_attr = 0o100755 << 16  # a regular file, executable
            zip_out.writestr(entry, (HERE / name).read_bytes())
    print(f"gradescope: wrote {out} (HEAD's tree, setup.sh and run_autograder at its root)",
          file=sys.stderr)
    return 0


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        sys.exit(2)
    sys.exit(main(sys.argv[1]))
