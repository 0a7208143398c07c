"""QGIS plugin: the hfbake Processing provider."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    from .plugin import HfbakePlugin

    return HfbakePlugin(iface)
