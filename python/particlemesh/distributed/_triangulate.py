def triangulate_tiled(*a, **k):
    raise NotImplementedError
