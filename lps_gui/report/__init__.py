"""The report: figures as plain data, pages as plain rows, and the PDF painters (Qt imported lazily)."""
