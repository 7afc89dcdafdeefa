package naogateway.launcher

import ch.qos.logback.classic.pattern.ClassicConverter
import ch.qos.logback.classic.spi.ILoggingEvent

import naogateway.api.Printable

/** The launcher log's `%safemsg`: the message with its control characters replaced ([[naogateway.api.Printable]]), so a
  * robot's or a peer's string logged anywhere cannot forge a log line or reach a terminal that shows the log.
  */
final class PrintableMessage extends ClassicConverter {
  override def convert(event: ILoggingEvent): String = Printable.text(event.getFormattedMessage)
}
