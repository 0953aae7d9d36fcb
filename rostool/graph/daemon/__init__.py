"""A private, per-user ROS 2 graph daemon: one long-lived graph of the selected backend that answers the
Graph protocol's read-only queries over a Unix-domain socket, so listings answer at once, and relays
subscriptions (a verb's reader in its warm graph), so `topic echo/hz/bw` need not join the graph at all.

- place.py: where a user's daemons live (a 0700 directory, checked before use) and which daemon serves
  an environment (its key: domain, backend, RMW, discovery and DDS profile variables);
- wire.py: the framed JSON messages on the socket (bounded size, timeouts);
- queries.py: the protocol methods the daemon serves and how their typed results travel;
- server.py: the daemon process; client.py: reaching, starting and stopping it;
- relay_server.py, relay_client.py: a relayed subscription, the daemon's side and the verb's;
- graph.py: `DaemonGraph`, the Graph the verbs get from open_graph() when a daemon may serve.
"""

NO_DAEMON_ENV = "ROSTOOL_NO_DAEMON"
