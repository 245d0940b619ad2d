"""A sphinx-gallery image scraper for lagcomp's figures and animations.

lagcomp draws on `matplotlib.figure.Figure` objects of its own, without pyplot, so the
default matplotlib scraper (which reads pyplot's figure list) never sees them.  This one
takes, after each code block, the figures and `matplotlib.animation.Animation` objects
bound to names in the example's namespace that it has not shown yet: a figure as a PNG,
an animation as an HTML player (`to_jshtml`), with its last frame as the thumbnail.
"""

from __future__ import annotations

import weakref
from textwrap import indent

from sphinx_gallery.scrapers import figure_rst

_shown: weakref.WeakSet = weakref.WeakSet()

_PLAYER = """
.. raw:: html

    <div class="sphx-glr-animation">
{0}
    </div>
"""


def _new_artists(namespace: dict):
    from matplotlib.animation import Animation
    from matplotlib.figure import Figure

    for value in list(namespace.values()):
        if isinstance(value, (Figure, Animation)) and value not in _shown:
            _shown.add(value)
            if isinstance(value, Animation):
                _shown.add(value._fig)
            yield value


def scrape(block, block_vars, gallery_conf, **kwargs) -> str:
    """Save the block's new figures and animations; return the reST that shows them."""
    from matplotlib.animation import Animation

    paths, players = [], []
    for artist, path in zip(_new_artists(block_vars["example_globals"]), block_vars["image_path_iterator"]):
        if isinstance(artist, Animation):
            players.append(_PLAYER.format(indent(artist.to_jshtml(), "    ")))
            artist._fig.savefig(path)
        else:
            artist.savefig(path)
            paths.append(path)
    return (figure_rst(paths, gallery_conf["src_dir"]) if paths else "") + "".join(players)
