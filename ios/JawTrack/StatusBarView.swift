// Adapts SwiftUI to JawTrackKit's StatusBar: lays out its items, link light, the capture plan's
// guidance (a line of its own) and notes, re-read four times a second so the light turns red
// when acknowledgements stop, without new frames.
import JawTrackKit
import SwiftUI

@MainActor
struct StatusBarView: View {
    let state: ScreenState

    var body: some View {
        TimelineView(.periodic(from: .now, by: 0.25)) { context in
            let bar = state.statusBar(now: context.date.timeIntervalSince1970)
            VStack(alignment: .leading, spacing: 3) {
                HStack(spacing: 10) {
                    ForEach(bar.items.indices, id: \.self) { i in
                        Text(bar.items[i].text).foregroundColor(Self.color(bar.items[i].tone))
                    }
                    if bar.link.shown {
                        Circle().fill(bar.link.green ? Color.green : Color.red).frame(width: 8, height: 8)
                        Text(bar.link.text).foregroundColor(bar.link.green ? Color.green : Color.red)
                    }
                }
                if let guidance = bar.guidance {
                    Text(guidance.text).font(.footnote.bold()).foregroundColor(Self.color(guidance.tone)).lineLimit(2)
                }
                ForEach(bar.notes.indices, id: \.self) { i in
                    Text(bar.notes[i].text).foregroundColor(Self.color(bar.notes[i].tone)).lineLimit(2)
                }
            }
            .font(.caption.monospacedDigit())
            .foregroundColor(.white)
            .padding(8)
            .background(Color.black.opacity(0.55))
            .clipShape(RoundedRectangle(cornerRadius: 8))
        }
    }

    nonisolated private static func color(_ tone: StatusTone) -> Color {
        switch tone {
        case .normal: return .white
        case .good: return .green
        case .warning: return .yellow
        case .problem: return .orange
        case .recording: return .red
        }
    }
}
