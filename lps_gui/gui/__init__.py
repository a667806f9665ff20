"""The PySide6 + pyqtgraph operator GUI (``lps-gui``)."""
from lps_gui.gui.refguard import protect_singletons

protect_singletons()  # PySide6 6.12 on Python 3.11: see refguard.py
