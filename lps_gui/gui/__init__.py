"""The PySide6 + pyqtgraph operator GUI (``lps-gui``)."""
