"""Registers the provider with QGIS's Processing registry (GUI and qgis_process alike)."""

from qgis.core import QgsApplication

from .provider import HfbakeProvider


class HfbakePlugin:
    def __init__(self, iface):
        self.iface = iface
        self.provider = None

    def initProcessing(self):  # noqa: N802
        self.provider = HfbakeProvider()
        QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self):  # noqa: N802
        self.initProcessing()

    def unload(self):
        if self.provider:
            QgsApplication.processingRegistry().removeProvider(self.provider)
