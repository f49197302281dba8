"""``python -m replication``: the command line, whose home is :mod:`replication.cli`."""
import sys

from replication.cli import main_closing_pipes

if __name__ == "__main__":
    sys.exit(main_closing_pipes())
