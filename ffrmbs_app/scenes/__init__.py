"""The built-in scenes (the thesis beam with a point mass, the sliding ball) and the cache of their preprocessed bodies."""
