"""The application layer: the ``hammerbound`` command line, the chapter's reproduction and
the markdown report. Nothing below this package imports it."""
