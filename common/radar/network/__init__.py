"""Fusion centre of multistatic networks (issue 29, docs/networks.md): many small
unsynchronised nodes, each a receiver with 1-3 transmitters, most measuring bistatic
range and range rate only. Equivalent measurements per base report, 3-D localisation
without azimuth, an asynchronous EKF and the `NetworkFusion` tracker. Pure."""
