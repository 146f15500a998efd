"""fuzzyfire.curate: the dataset model, formats, safe image IO and curation (the base layer)."""
