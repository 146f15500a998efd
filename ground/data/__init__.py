"""The dataset model: COCO-canonical image and box records, the readers and writers of every format, class
names, problems found in a user's data, manifests, fingerprints and content hold-outs."""
