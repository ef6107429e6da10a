"""Live view for Foxglove (no rclpy): decimation, tracking frames, schemas, the WebSocket server, the view itself."""
