"""One module per tool; each is a thin click layer over the library."""
