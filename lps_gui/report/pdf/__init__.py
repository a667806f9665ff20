"""The painters: the page flow on a QPdfWriter, plots, text fitting, the report, intrinsics and targets PDFs."""
