"""Shared by the benchmark drivers: what machine the numbers were measured on."""
import platform
import subprocess


def cpu_model() -> str:
    """The CPU's model name (lscpu), else what platform knows."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"
