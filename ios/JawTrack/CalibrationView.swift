// Adapts SwiftUI to JawTrackKit's CalibrationScreen and CalibrationController: lays out the
// marker calibration panel over the camera preview (progress per marker, Solve, the per-tag
// result, Save, the replace question) and forwards every tap to the controller.
import JawTrackKit
import SwiftUI

@MainActor
struct CalibrationView: View {
    let screen: CalibrationScreen
    let controller: CalibrationController

    var body: some View {
        VStack(alignment: .leading, spacing: 8) {
            HStack {
                Text(CalibrationText.title).font(.headline)
                Spacer()
                Button(CalibrationText.close) { controller.close() }
            }
            ScrollView {
                content
                    .frame(maxWidth: .infinity, alignment: .leading)
            }
            .frame(maxHeight: 320)
            buttons
        }
        .font(.footnote)
        .padding(12)
        .background(.ultraThinMaterial, in: RoundedRectangle(cornerRadius: 14))
        .padding(8)
        .alert(screen.message?.title ?? "", isPresented: messageShown, presenting: screen.message) { _ in
            Button("OK", role: .cancel) {}
        } message: { message in
            Text(message.text)
        }
        .confirmationDialog(CalibrationText.replaceTitle, isPresented: replaceAsked, titleVisibility: .visible) {
            Button(CalibrationText.replace, role: .destructive) { controller.save(replacing: true) }
            Button(CalibrationText.cancel, role: .cancel) { controller.keepExistingFile() }
        } message: {
            Text(CalibrationText.replaceText)
        }
    }

    @ViewBuilder private var content: some View {
        VStack(alignment: .leading, spacing: 6) {
            switch screen.phase {
            case .collecting, .solving, .closed:
                Text(CalibrationText.instructions)
                lines(screen.bodyLines)
                if let hint = screen.hint { Text(hint).foregroundColor(.yellow) }
                Text(screen.readiness).bold()
            case .solved, .saved:
                lines(screen.summary)
                if let warning = screen.warning { Text(warning).foregroundColor(.orange) }
                lines(screen.findings)
                table
            }
        }
    }

    private var table: some View {
        Grid(alignment: .leading, horizontalSpacing: 10, verticalSpacing: 3) {
            GridRow {
                ForEach(CalibrationText.columns.indices, id: \.self) { i in Text(CalibrationText.columns[i]).bold() }
            }
            ForEach(screen.rows) { row in
                let tone: Color = row.calibrated ? .primary : .secondary
                GridRow {
                    Text("\(row.body) \(row.tag)").foregroundColor(tone)
                    Text(row.views).foregroundColor(tone)
                    Text(row.shift).foregroundColor(tone)
                    Text(row.turn).foregroundColor(tone)
                    Text(row.error).foregroundColor(tone)
                }
            }
        }
        .font(.caption.monospacedDigit())
    }

    @ViewBuilder private var buttons: some View {
        HStack(spacing: 10) {
            switch screen.phase {
            case .collecting:
                Button(CalibrationText.solve) { controller.solve() }
                    .buttonStyle(.borderedProminent)
                    .disabled(!screen.canSolve)
                Button(CalibrationText.startOver) { controller.startOver() }
                    .buttonStyle(.bordered)
            case .solving:
                ProgressView()
                Text(CalibrationText.solving)
            case .solved:
                Button(CalibrationText.save) { controller.save() }
                    .buttonStyle(.borderedProminent)
                    .disabled(!screen.canSave)
                Button(CalibrationText.addViews) { controller.addViews() }
                    .buttonStyle(.bordered)
            case .saved, .closed:
                EmptyView()
            }
        }
    }

    private func lines(_ texts: [String]) -> some View {
        ForEach(texts.indices, id: \.self) { i in Text(texts[i]) }
    }

    private var messageShown: Binding<Bool> {
        Binding(get: { screen.message != nil }, set: { shown in if !shown { controller.dismissMessage() } })
    }

    private var replaceAsked: Binding<Bool> {
        Binding(get: { screen.confirmReplace }, set: { asked in if !asked { controller.keepExistingFile() } })
    }
}
