"""Build the book (``bash scripts/docs``): stage its source in docs/_build/source
(replication.study.book.stage: the pages of docs/, the generated blocks, the executed notebooks as
stored) and render it with Sphinx and MyST-NB into docs/_build/html, warnings as errors. Exit
status: Sphinx's (0 built); 2 when the source cannot be staged."""
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "docs" / "_build"


def main(argv=None) -> int:
    from sphinx.cmd.build import build_main

    from replication import _PUBLIC
    from replication.study.book import stage

    try:
        source = stage(BUILD / "source", public=_PUBLIC, root=ROOT)
    except (ValueError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    args = ["-W", "--keep-going", "-q", "-b", "html", "-d", str(BUILD / "doctrees"), str(source), str(BUILD / "html")]
    return build_main([*args, *(sys.argv[1:] if argv is None else argv)])


if __name__ == "__main__":
    sys.exit(main())
