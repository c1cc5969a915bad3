"""Built-in models, one module per family; the registry imports them
(``sphfoam.registry.MODEL_MODULES``)."""
