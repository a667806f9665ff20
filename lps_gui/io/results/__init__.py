"""results.json: the one document, its typed sections, the writer, the reader and the history of runs."""
