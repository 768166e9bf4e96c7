"""RollBall's desktop app: the 2011 MATLAB window rebuilt with PySide6 and pyqtgraph.

Qt is imported only when the app starts (``main``), so ``import app`` stays cheap.
"""


def main(argv=None) -> int:
    from .main import main as run

    return run(argv)
