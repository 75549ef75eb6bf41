"""The py_trees leaves of homebot and the trees built from them."""
