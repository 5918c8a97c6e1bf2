"""The paper's whole study on a parameter set: figures, tables and the report."""

from .runner import run
from .studies import PAPER, StudySettings

__all__ = ["PAPER", "StudySettings", "run"]
