"""adaptseg's Python tools, one module per tool (python/README.md lists them): field conversion
and checks, the segmentation networks' training (training/) and evaluation, the tables and
figures of the experiments' outputs. Each tool runs as `python3 -m adaptseg_tools.NAME`, from the
source tree with PYTHONPATH=python.
"""
from pathlib import Path

# The repository this package lies in (python/adaptseg_tools/): the tools' default fields and
# models are its examples/data and examples/models.
REPO = Path(__file__).resolve().parents[2]
