"""RollBall's desktop app: the 2011 MATLAB window rebuilt with PySide6 and pyqtgraph.

Qt is imported only when the app starts (``main``), so importing it stays cheap. It lives in the
folder ``app/`` and is installed as ``rollball_app`` (``pyproject.toml``), so no top-level ``app``
reaches site-packages; ``python -m app`` still runs it from a checkout.
"""


def main(argv=None) -> int:
    from .main import main as run

    return run(argv)
