"""Write docs/reproduction.md: the article's switching times next to ours, from the case files.

Usage: python scripts/reproduction.py [--check]

With --check, exit 1 if docs/reproduction.md differs from what the case files give now.
"""

import sys
from pathlib import Path

from oscillator.report.reproduction import render_markdown

INSTANCES = [f"instance-{i}" for i in range(1, 6)]
TARGET = Path(__file__).resolve().parents[1] / "docs" / "reproduction.md"


def main(argv: list[str]) -> int:
    text = render_markdown(INSTANCES)
    if "--check" in argv:
        current = TARGET.read_text(encoding="utf-8") if TARGET.exists() else ""
        if current != text:
            print(f"{TARGET} is out of date; run: python scripts/reproduction.py", file=sys.stderr)
            return 1
        print(f"{TARGET} is up to date")
        return 0
    TARGET.write_text(text, encoding="utf-8")
    print(f"wrote {TARGET}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
