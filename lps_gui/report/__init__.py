"""The report: figures as plain data, pages as plain rows, the PDF painters (Qt imported lazily), and the
registry of result sections the PDF and the GUI read."""
