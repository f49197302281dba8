"""Former home of the lab recordings' writer and loader, kept so that old imports work: see :mod:`replication.lab.recording`."""
from .lab.recording import FILES, default_lab_dir, load_lab, write_lab

__all__ = ["FILES", "write_lab", "load_lab", "default_lab_dir"]
