"""What speaks the protocol: wire codec, network (simulated and UDP), sans-IO engines, nodes."""
