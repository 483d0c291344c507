"""The ``lbl-illum`` command line: one module per command family, the shared progress bar."""
