"""One module per ``groundstation`` subcommand (see ``groundstation.cli``)."""
