"""The library functions behind the CLI's verbs, one small module per verb (faced by ``snncc.api``)."""
