"""What a plot is and every plot of a report, as plain data: the GUI (pyqtgraph) and the PDF draw the same."""
