#pragma once
// Private to localize/cad_*.cpp: the one place that touches OpenCASCADE's process-wide
// data-exchange state. Never include it from a public header (OpenCASCADE must not leak).

#include <IGESControl_Controller.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_SequenceOfPrinters.hxx>
#include <STEPControl_Controller.hxx>
#include <Standard_Failure.hxx>
#include <mutex>
#include <string>

#include "core/error.hpp"

namespace lasercell::localize::internal {

/// While alive: holds the lock on OpenCASCADE's static settings (Interface_Static is one table
/// per process), has the STEP and IGES controllers registered (they create the settings), sets
/// the session unit to millimetres, and mutes OpenCASCADE's default messenger, which otherwise
/// prints transfer statistics to stdout (libraries never print). Restores the printers on exit.
class OcctSession {
 public:
  OcctSession() : lock_(Mutex()) {
    STEPControl_Controller::Init();
    IGESControl_Controller::Init();
    SetStatic("xstep.cascade.unit", "MM");
    Message_SequenceOfPrinters& printers = Message::DefaultMessenger()->ChangePrinters();
    saved_printers_ = printers;
    printers.Clear();
  }
  ~OcctSession() { Message::DefaultMessenger()->ChangePrinters() = saved_printers_; }
  OcctSession(const OcctSession&) = delete;
  OcctSession& operator=(const OcctSession&) = delete;

  /// Sets a data-exchange setting; a refused value is a bug here (names are fixed in the code).
  static void SetStatic(const char* name, const char* value) {
    LASERCELL_CHECK(Interface_Static::SetCVal(name, value),
                    std::string("OpenCASCADE refused ") + name + " = " + value);
  }
  /// Integer variant of SetStatic.
  static void SetStatic(const char* name, int value) {
    LASERCELL_CHECK(Interface_Static::SetIVal(name, value),
                    std::string("OpenCASCADE refused ") + name + " = " + std::to_string(value));
  }

 private:
  static std::mutex& Mutex() {
    static std::mutex mutex;
    return mutex;
  }
  std::unique_lock<std::mutex> lock_;
  Message_SequenceOfPrinters saved_printers_;
};

/// The message of an OpenCASCADE exception with its type, e.g. "Standard_ConstructionError: ...".
inline std::string DescribeFailure(const Standard_Failure& failure) {
  std::string text = failure.DynamicType()->Name();
  const char* message = failure.GetMessageString();
  if (message != nullptr && message[0] != '\0') text += std::string(": ") + message;
  return text;
}

}  // namespace lasercell::localize::internal
