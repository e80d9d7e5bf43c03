"""toolconf's derivation stage: model description -> SymPy derivation, checked by CasADi -> JSON IR."""
