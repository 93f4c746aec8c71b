"""From the options to the audited plan every product is built from: the episodes' roles and
realised specs (`plan`), a mix of types taking turns (`mix`), the confound audit (`audit`)."""
