#!/usr/bin/python3
"""Listens to a paint session's statistics until interrupted and writes what was measured over the whole session.

Usage: /usr/bin/python3 scripts/session_summary.py OUTPUT.txt [PAINT_STATS.csv]
       (stop it with SIGINT; the summary is written then; PAINT_STATS.csv: the paint model's memory-relevant stats
       per message: unix time, active surfels, children, undo journal bytes, heap in use and freed but held)
Topics: paint_stats (relaxed_connectivity/PaintStats), paint_renderer/stats (PaintRenderStats), haptic/stats
(HapticLoopStats). Rates are over the periods in which something happened (painting events, rendered frames);
latencies are the largest per-period percentiles and the renderer's own over the whole session (device pose stamp
-> image).
"""
import signal
import sys

import rospy
from relaxed_connectivity.msg import HapticLoopStats, PaintRenderStats, PaintStats


class Summary:
    def __init__(self):
        self.paint = []
        self.render = []
        self.haptic = None

    def write(self, path):
        lines = ["paint session summary (scripts/session_summary.py)"]
        painting = [m for m in self.paint if m.events_per_second > 0]
        if self.paint:
            last = self.paint[-1]
            lines.append("object: %d originals, %d children, %d active surfels, %d wet; brush %s, paint %s"
                         % (last.originals, last.children, last.active_surfels, last.wet_surfels, last.brush,
                            last.paint))
            lines.append("undo strokes: %d; rejected messages: %d; brush instabilities: %d"
                         % (last.undo_strokes, last.rejected_messages, last.instabilities))
        if painting:
            n = len(painting)
            lines.append("paint events: %.1f per second while painting (%d seconds), per tick: brush %.3f ms, "
                         "transfer %.3f ms, background %.3f ms, publish %.3f ms"
                         % (sum(m.events_per_second for m in painting) / n, n,
                            sum(m.brush_ms for m in painting) / n, sum(m.transfer_ms for m in painting) / n,
                            sum(m.background_ms for m in painting) / n, sum(m.publish_ms for m in painting) / n))
        frames = sum(m.frames for m in self.render)
        if frames:
            full = sum(m.full_updates for m in self.render)
            diff = sum(m.differential_updates for m in self.render)
            full_ms = sum(m.full_update_ms * m.full_updates for m in self.render) / max(full, 1)
            diff_ms = sum(m.differential_update_ms * m.differential_updates for m in self.render) / max(diff, 1)
            busy = [m for m in self.render if m.deltas > 0]
            lines.append("renderer: %d frames, %d full updates (mean %.1f ms), %d differential (mean %.2f ms, "
                         "max %.2f ms), %d deltas of %d surfels, brush drawn in %.2f ms on average"
                         % (frames, full, full_ms, diff, diff_ms,
                            max([m.differential_update_max_ms for m in self.render] or [0]),
                            sum(m.deltas for m in self.render), sum(m.delta_surfels for m in self.render),
                            sum(m.brush_ms * m.frames for m in self.render) / frames))
            if busy:
                lines.append("frames per second while painting: %.1f; latency device pose -> image: p50 %.1f ms, "
                             "p99 %.1f ms, max %.1f ms (largest per-second values)"
                             % (sum(m.frames for m in busy) / len(busy), max(m.latency_p50_ms for m in busy),
                                max(m.latency_p99_ms for m in busy), max(m.latency_max_ms for m in busy)))
            reasons = {}
            for m in self.render:
                if m.full_updates:
                    reasons[m.last_full_update_reason] = reasons.get(m.last_full_update_reason, 0) + m.full_updates
            lines.append("full updates by (last) reason per second: " +
                         ", ".join("%s %d" % kv for kv in sorted(reasons.items())))
            last = self.render[-1]
            if last.session_latency_count:
                lines.append("latency device pose -> image over the session: p50 %.1f ms, p99 %.1f ms, max %.1f ms "
                             "(%d deltas)" % (last.session_latency_p50_ms, last.session_latency_p99_ms,
                                              last.session_latency_max_ms, last.session_latency_count))
            lines.append("latency p99 per second while painting [ms]: " +
                         " ".join("%.0f" % m.latency_p99_ms for m in busy))
            last = self.render[-1]
            lines.append("renderer copy: %d surfels; sequence gaps %d, resyncs %d, rejected messages %d"
                         % (last.surfels, last.sequence_gaps, last.resyncs, last.rejected_messages))
        if self.haptic is not None:
            h = self.haptic
            lines.append("haptic loop: %.0f Hz nominal, %d ticks, %d missed, period p99 %.3f ms, jitter p99 %.3f ms"
                         % (h.rate, h.ticks, h.missed_ticks, 1e3 * h.period_p99, 1e3 * h.jitter_p99))
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")
        print("\n".join(lines))


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rospy.init_node("session_summary", anonymous=True, disable_signals=True)
    s = Summary()
    rospy.Subscriber("paint_stats", PaintStats, s.paint.append, queue_size=100)
    rospy.Subscriber("paint_renderer/stats", PaintRenderStats, s.render.append, queue_size=100)
    rospy.Subscriber("haptic/stats", HapticLoopStats, lambda m: setattr(s, "haptic", m), queue_size=10)
    stop = []
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    while not stop:
        rospy.sleep(0.2)
    s.write(sys.argv[1])
    if len(sys.argv) > 2:
        with open(sys.argv[2], "w") as f:
            f.write("unix_time,active_surfels,children,journal_bytes,heap_in_use_bytes,heap_free_bytes\n")
            for m in s.paint:
                f.write("%.3f,%d,%d,%d,%d,%d\n" % (m.header.stamp.to_sec(), m.active_surfels, m.children,
                                                  m.journal_bytes, m.heap_in_use_bytes, m.heap_free_bytes))
    rospy.signal_shutdown("done")


if __name__ == "__main__":
    main()
